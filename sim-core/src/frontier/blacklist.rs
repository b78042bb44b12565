//! Goals the robot could not reach: candidates near them are skipped.

use crate::geom::Vec2;

/// Blacklisted goals, each with a radius, in insertion order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Blacklist {
    pub entries: Vec<BlacklistEntry>,
    /// Entries ever added (forgiven ones included).
    added: usize,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlacklistEntry {
    pub goal_m: Vec2,
    pub radius_m: f64,
    /// Given up (no progress, or standing still) rather than found unreachable: may be
    /// forgiven.
    pub given_up: bool,
    /// Reached and looked at: the robot stood there facing the unknown space behind the
    /// frontier, and the frontier's cells within the radius stayed frontier (they cannot be
    /// seen from there).
    pub looked: bool,
}

impl Blacklist {
    pub fn new() -> Self {
        Self::default()
    }

    /// Blacklists a goal that cannot be reached.
    pub fn add(&mut self, goal_m: Vec2, radius_m: f64) {
        self.push(goal_m, radius_m, false, false);
    }

    /// Blacklists a goal given up (no progress toward it); [`Blacklist::forgive`] lifts it.
    pub(crate) fn give_up(&mut self, goal_m: Vec2, radius_m: f64) {
        self.push(goal_m, radius_m, true, false);
    }

    /// Blacklists a goal reached and looked at whose frontier is still there.
    pub fn looked(&mut self, goal_m: Vec2, radius_m: f64) {
        self.push(goal_m, radius_m, false, true);
    }

    /// [`Blacklist::looked`], but [`Blacklist::forgive`] lifts it (a team's: a teammate may have
    /// stood in the view).
    pub(crate) fn looked_for_now(&mut self, goal_m: Vec2, radius_m: f64) {
        self.push(goal_m, radius_m, true, true);
    }

    fn push(&mut self, goal_m: Vec2, radius_m: f64, given_up: bool, looked: bool) {
        self.entries.push(BlacklistEntry {
            goal_m,
            radius_m: radius_m.max(0.0),
            given_up,
            looked,
        });
        self.added += 1;
    }

    /// Whether `p` lies within the radius of a goal reached and looked at.
    pub fn looked_at(&self, p: Vec2) -> bool {
        self.entries
            .iter()
            .any(|e| e.looked && (p - e.goal_m).norm_squared() <= e.radius_m * e.radius_m)
    }

    /// Whether `p` lies within the radius of a goal given up.
    pub(crate) fn given_up_at(&self, p: Vec2) -> bool {
        self.entries
            .iter()
            .any(|e| e.given_up && (p - e.goal_m).norm_squared() <= e.radius_m * e.radius_m)
    }

    /// Removes the goals given up; returns how many.
    pub(crate) fn forgive(&mut self) -> usize {
        let before = self.entries.len();
        self.entries.retain(|e| !e.given_up);
        before - self.entries.len()
    }

    /// Entries ever added, forgiven ones included.
    pub fn added(&self) -> usize {
        self.added
    }

    /// Whether `p` lies within the radius of a blacklisted goal (boundary included).
    pub fn contains(&self, p: Vec2) -> bool {
        self.entries
            .iter()
            .any(|e| (p - e.goal_m).norm_squared() <= e.radius_m * e.radius_m)
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_within_the_radius_are_skipped() {
        let mut b = Blacklist::new();
        assert!(!b.contains(Vec2::new(0.0, 0.0)));
        b.add(Vec2::new(1.0, 1.0), 0.5);
        assert!(b.contains(Vec2::new(1.3, 1.3)));
        assert!(b.contains(Vec2::new(1.5, 1.0)));
        assert!(!b.contains(Vec2::new(1.4, 1.4)));
        b.add(Vec2::new(5.0, 5.0), -1.0); // negative radius: only the goal itself
        assert!(b.contains(Vec2::new(5.0, 5.0)));
        assert!(!b.contains(Vec2::new(5.0, 5.01)));
        assert_eq!(b.len(), 2);
    }

    #[test]
    fn only_goals_given_up_are_forgiven() {
        let mut b = Blacklist::new();
        b.add(Vec2::new(0.0, 0.0), 0.5);
        b.give_up(Vec2::new(3.0, 0.0), 0.5);
        b.give_up(Vec2::new(6.0, 0.0), 0.5);
        assert!(b.contains(Vec2::new(3.0, 0.0)));
        assert_eq!(b.forgive(), 2);
        assert!(!b.contains(Vec2::new(3.0, 0.0)) && !b.contains(Vec2::new(6.0, 0.0)));
        assert!(b.contains(Vec2::new(0.0, 0.0)));
        assert_eq!((b.len(), b.added()), (1, 3));
        assert_eq!(b.forgive(), 0);
    }
}
