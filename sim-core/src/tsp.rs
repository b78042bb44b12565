//! Open travelling-salesman paths: from a fixed start through every node once, not returning,
//! by a nearest-neighbour start improved by 2-opt and Or-opt moves until none shortens it
//! (the usual heuristics; fast and deterministic for the dozens of nodes of a decision). Used by
//! `frontier-tsp` (Kulich, Faigl and Přeučil, ICRA 2011).

/// Lengths above this count as this (an infinite length, no path, would make every sum equal).
const FAR: f64 = 1e9;

/// The nodes' order in a short open path from the start: `from_start[i]` is the length from the
/// start to node `i`, `between[i * n + j]` from node `i` to node `j` (`n = from_start.len()`).
/// Lengths that are not finite count as very long. At most `max_passes` rounds of improving
/// moves are made (each round tries every move once).
pub(crate) fn open_path(from_start: &[f64], between: &[f64], max_passes: usize) -> Vec<usize> {
    let n = from_start.len();
    if n == 0 || between.len() != n * n {
        return (0..n).collect();
    }
    let costs = Costs {
        from_start,
        between,
        n,
    };
    let mut order = costs.nearest_neighbour();
    for _ in 0..max_passes {
        let improved = two_opt(&costs, &mut order) | or_opt(&costs, &mut order);
        if !improved {
            break;
        }
    }
    order
}

/// The length of the open path `order` from the start.
pub fn path_length(from_start: &[f64], between: &[f64], order: &[usize]) -> f64 {
    let costs = Costs {
        from_start,
        between,
        n: from_start.len(),
    };
    costs.length(order)
}

struct Costs<'a> {
    from_start: &'a [f64],
    between: &'a [f64],
    n: usize,
}

impl Costs<'_> {
    /// From `a` (`None`: the start) to `b` (`None`: the path's end, which costs nothing).
    fn d(&self, a: Option<usize>, b: Option<usize>) -> f64 {
        let v = match (a, b) {
            (_, None) => 0.0,
            (None, Some(b)) => self.from_start[b],
            (Some(a), Some(b)) => self.between[a * self.n + b],
        };
        if v.is_finite() {
            v.min(FAR)
        } else {
            FAR
        }
    }

    fn length(&self, order: &[usize]) -> f64 {
        let mut prev = None;
        let mut sum = 0.0;
        for &i in order {
            sum += self.d(prev, Some(i));
            prev = Some(i);
        }
        sum
    }

    /// From the start, always the nearest node not yet visited (the first of equals).
    fn nearest_neighbour(&self) -> Vec<usize> {
        let mut left: Vec<usize> = (0..self.n).collect();
        let mut order = Vec::with_capacity(self.n);
        let mut at = None;
        while !left.is_empty() {
            let mut best = 0;
            for k in 1..left.len() {
                if self.d(at, Some(left[k])) < self.d(at, Some(left[best])) {
                    best = k;
                }
            }
            let next = left.remove(best);
            order.push(next);
            at = Some(next);
        }
        order
    }
}

/// A change must save more than this (m) to be made (rounding must not make moves cycle).
const EPS: f64 = 1e-9;

/// One round of 2-opt: reverses `order[i..=j]` wherever that shortens the path.
fn two_opt(c: &Costs<'_>, order: &mut [usize]) -> bool {
    let n = order.len();
    let at = |order: &[usize], k: usize| order.get(k).copied();
    let mut improved = false;
    for i in 0..n {
        for j in i + 1..n {
            let before = if i == 0 { None } else { Some(order[i - 1]) };
            let after = at(order, j + 1);
            let now = c.d(before, Some(order[i])) + c.d(Some(order[j]), after);
            let then = c.d(before, Some(order[j])) + c.d(Some(order[i]), after);
            // Reversing also reverses the legs inside (asymmetric lengths): compare whole.
            if then + EPS < now {
                let mut trial = order.to_vec();
                trial[i..=j].reverse();
                if c.length(&trial) + EPS < c.length(order) {
                    order.copy_from_slice(&trial);
                    improved = true;
                }
            }
        }
    }
    improved
}

/// One round of Or-opt: moves a run of 1 to 3 nodes elsewhere in the path wherever that
/// shortens it.
fn or_opt(c: &Costs<'_>, order: &mut Vec<usize>) -> bool {
    let mut improved = false;
    for len in 1..=3usize {
        let mut i = 0;
        while i + len <= order.len() {
            let best = best_insertion(c, order, i, len);
            if let Some(trial) = best {
                *order = trial;
                improved = true;
            }
            i += 1;
        }
    }
    improved
}

/// The shortest path made by moving `order[i..i + len]` to another place, if shorter.
fn best_insertion(c: &Costs<'_>, order: &[usize], i: usize, len: usize) -> Option<Vec<usize>> {
    let base = c.length(order);
    let run: Vec<usize> = order[i..i + len].to_vec();
    let rest: Vec<usize> = order[..i]
        .iter()
        .chain(&order[i + len..])
        .copied()
        .collect();
    let mut best: Option<(f64, Vec<usize>)> = None;
    for k in 0..=rest.len() {
        if k == i {
            continue;
        }
        let mut trial = rest[..k].to_vec();
        trial.extend(&run);
        trial.extend(&rest[k..]);
        let l = c.length(&trial);
        if l + EPS < best.as_ref().map_or(base, |b| b.0) {
            best = Some((l, trial));
        }
    }
    best.map(|b| b.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on the plane: lengths from the start (the origin) and between them.
    fn plane(points: &[(f64, f64)]) -> (Vec<f64>, Vec<f64>) {
        let d = |a: (f64, f64), b: (f64, f64)| ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt();
        let from: Vec<f64> = points.iter().map(|p| d((0.0, 0.0), *p)).collect();
        let mut between = Vec::new();
        for a in points {
            for b in points {
                between.push(d(*a, *b));
            }
        }
        (from, between)
    }

    /// All orders of `n` nodes.
    fn permutations(n: usize) -> Vec<Vec<usize>> {
        if n == 0 {
            return vec![Vec::new()];
        }
        let mut out = Vec::new();
        for p in permutations(n - 1) {
            for k in 0..=p.len() {
                let mut q = p.clone();
                q.insert(k, n - 1);
                out.push(q);
            }
        }
        out
    }

    #[test]
    fn points_on_a_line_are_visited_in_order_from_the_near_end() {
        // The nearest neighbour goes to 1 first (a tie with -1), back to -1 and -2, then out to
        // 3 and 6: 12 m; the shortest goes to -1 and -2 first, then out: 10 m.
        let pts = [(1.0, 0.0), (-1.0, 0.0), (3.0, 0.0), (-2.0, 0.0), (6.0, 0.0)];
        let (from, between) = plane(&pts);
        let order = open_path(&from, &between, 50);
        let mut first_two = order[..2].to_vec();
        first_two.sort_unstable();
        assert_eq!((first_two, &order[2..]), (vec![1, 3], &[0, 2, 4][..]));
        assert!((path_length(&from, &between, &order) - 10.0).abs() < 1e-9);
    }

    /// On random instances of up to 7 nodes: a permutation, never longer than the nearest
    /// neighbour's, within 10 % of the optimum (found by trying every order), the same twice.
    #[test]
    fn paths_are_short_permutations() {
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 40.0 - 20.0
        };
        for case in 0..60 {
            let n = 1 + case % 7;
            let pts: Vec<(f64, f64)> = (0..n).map(|_| (next(), next())).collect();
            let (from, between) = plane(&pts);
            let order = open_path(&from, &between, 50);
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..n).collect::<Vec<_>>(), "case {case}");
            let costs = Costs {
                from_start: &from,
                between: &between,
                n,
            };
            let length = costs.length(&order);
            assert!(length <= costs.length(&costs.nearest_neighbour()) + 1e-9);
            let best = permutations(n)
                .iter()
                .map(|p| costs.length(p))
                .fold(f64::INFINITY, f64::min);
            assert!(
                length <= best * 1.1 + 1e-9,
                "case {case}: {length} against {best}"
            );
            assert_eq!(order, open_path(&from, &between, 50));
        }
    }

    /// Nodes without a path are visited last, and lengths of the wrong size are not trusted.
    #[test]
    fn unreachable_nodes_go_last_and_bad_input_gives_the_given_order() {
        let from = [5.0, f64::INFINITY, 1.0];
        let between = [
            0.0,
            f64::INFINITY,
            4.0,
            f64::INFINITY,
            0.0,
            f64::INFINITY,
            4.0,
            f64::INFINITY,
            0.0,
        ];
        assert_eq!(open_path(&from, &between, 50), vec![2, 0, 1]);
        assert_eq!(open_path(&from, &between[..4], 50), vec![0, 1, 2]);
        assert!(open_path(&[], &[], 50).is_empty());
    }
}
