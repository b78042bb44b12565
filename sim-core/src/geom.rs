//! Plain geometry in world metres (x right, y up, angles in radians counter-clockwise).

/// A point or vector in world metres.
pub type Vec2 = nalgebra::Vector2<f64>;

/// A robot pose in the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub x_m: f64,
    pub y_m: f64,
    pub theta_rad: f64,
}

impl Pose {
    pub const fn new(x_m: f64, y_m: f64, theta_rad: f64) -> Self {
        Self {
            x_m,
            y_m,
            theta_rad,
        }
    }
    pub fn position(&self) -> Vec2 {
        Vec2::new(self.x_m, self.y_m)
    }
    /// `self ∘ other`: `other` expressed in `self`'s frame, brought to the world.
    pub fn compose(&self, other: &Pose) -> Pose {
        let (s, c) = self.theta_rad.sin_cos();
        Pose::new(
            self.x_m + c * other.x_m - s * other.y_m,
            self.y_m + s * other.x_m + c * other.y_m,
            wrap_angle(self.theta_rad + other.theta_rad),
        )
    }
    /// The pose `d` such that `self.compose(d) == other`.
    pub fn between(&self, other: &Pose) -> Pose {
        let (s, c) = self.theta_rad.sin_cos();
        let dx = other.x_m - self.x_m;
        let dy = other.y_m - self.y_m;
        Pose::new(
            c * dx + s * dy,
            -s * dx + c * dy,
            wrap_angle(other.theta_rad - self.theta_rad),
        )
    }
}

/// `x.floor()`, bit for bit (signed zeros, infinities and NaN included), without a call:
/// without SSE4.1 the standard library's `floor` is an out-of-line software routine, and cell
/// lookups (`floor(x) as i32`) are in every hot loop of the kernel.
#[inline(always)]
pub fn floor_f64(x: f64) -> f64 {
    // 2^52: from there on every f64 is an integer (and NaN fails the test).
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = x as i64 as f64; // truncated toward zero, exact in this range
        if t > x {
            t - 1.0
        } else {
            t.copysign(x)
        }
    } else {
        x
    }
}

/// `x.floor() as i32`, bit for bit (saturating, NaN to 0), without a call (see [`floor_f64`]).
#[inline(always)]
pub fn floor_i32(x: f64) -> i32 {
    // Truncated toward zero (saturating, NaN to 0), then one less where that rounded up.
    let t = x as i32;
    t.saturating_sub(((t as f64) > x) as i32)
}

/// Wraps an angle to (-pi, pi].
pub fn wrap_angle(a: f64) -> f64 {
    let mut a = a % std::f64::consts::TAU;
    if a <= -std::f64::consts::PI {
        a += std::f64::consts::TAU;
    } else if a > std::f64::consts::PI {
        a -= std::f64::consts::TAU;
    }
    a
}

/// Angular distance modulo pi.
pub fn angle_diff_mod_pi(a: f64, b: f64) -> f64 {
    let d = rem_pi(a - b);
    d.min(std::f64::consts::PI - d)
}

/// `x.rem_euclid(std::f64::consts::PI)`, bit for bit, without its division (`fmod`) in the usual case of an
/// angle within pi of 0: there `x % std::f64::consts::PI` is `x` exactly.
#[inline]
pub fn rem_pi(x: f64) -> f64 {
    if x.abs() < std::f64::consts::PI {
        if x < 0.0 {
            x + std::f64::consts::PI
        } else {
            x
        }
    } else {
        x.rem_euclid(std::f64::consts::PI)
    }
}

/// A line segment in world metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub a: Vec2,
    pub b: Vec2,
}

impl Segment {
    pub fn new(a: Vec2, b: Vec2) -> Self {
        Self { a, b }
    }
    pub fn length_m(&self) -> f64 {
        (self.b - self.a).norm()
    }

    /// Euclidean distance from `p` to the closest point of the segment.
    pub fn distance_to(&self, p: Vec2) -> f64 {
        let d = self.b - self.a;
        let len2 = d.norm_squared();
        let t = if len2 > 0.0 {
            ((p - self.a).dot(&d) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (self.a + d * t - p).norm()
    }
}

/// An axis-aligned box in world metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: Vec2,
    pub max: Vec2,
}

impl Aabb {
    pub fn empty() -> Self {
        Self {
            min: Vec2::new(f64::INFINITY, f64::INFINITY),
            max: Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        }
    }
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y)
    }
    pub fn grow(&mut self, p: Vec2) {
        self.min = self.min.inf(&p);
        self.max = self.max.sup(&p);
    }
    pub fn width_m(&self) -> f64 {
        (self.max.x - self.min.x).max(0.0)
    }
    pub fn height_m(&self) -> f64 {
        (self.max.y - self.min.y).max(0.0)
    }
    pub fn contains(&self, p: Vec2) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y
    }
}

/// A simple polygon (no self-intersections), vertices in order, implicitly closed
/// (the last vertex is *not* a repeat of the first).
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    pub vertices: Vec<Vec2>,
}

impl Polygon {
    pub fn new(vertices: Vec<Vec2>) -> Self {
        Self { vertices }
    }

    /// An axis-aligned rectangle.
    pub fn rect(min: Vec2, max: Vec2) -> Self {
        Self::new(vec![
            min,
            Vec2::new(max.x, min.y),
            max,
            Vec2::new(min.x, max.y),
        ])
    }

    /// The rectangle of a wall of `thickness_m` around the segment `a`-`b`
    /// (extended by half the thickness at both ends, so that walls meeting at a corner close it).
    pub fn thick_segment(a: Vec2, b: Vec2, thickness_m: f64) -> Self {
        let d = b - a;
        let len = d.norm();
        let h = thickness_m / 2.0;
        if len <= f64::EPSILON {
            return Self::rect(a - Vec2::new(h, h), a + Vec2::new(h, h));
        }
        let u = d / len;
        let n = Vec2::new(-u.y, u.x) * h;
        let a2 = a - u * h;
        let b2 = b + u * h;
        Self::new(vec![a2 - n, b2 - n, b2 + n, a2 + n])
    }

    /// Signed area (positive when counter-clockwise).
    pub fn signed_area_m2(&self) -> f64 {
        let n = self.vertices.len();
        let mut s = 0.0;
        for i in 0..n {
            let p = self.vertices[i];
            let q = self.vertices[(i + 1) % n];
            s += p.x * q.y - q.x * p.y;
        }
        s / 2.0
    }

    pub fn area_m2(&self) -> f64 {
        self.signed_area_m2().abs()
    }

    /// Even-odd point-in-polygon test.
    pub fn contains(&self, p: Vec2) -> bool {
        let n = self.vertices.len();
        let mut inside = false;
        let mut j = n.wrapping_sub(1);
        for i in 0..n {
            let a = self.vertices[i];
            let b = self.vertices[j];
            if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
                inside = !inside;
            }
            j = i;
        }
        inside
    }

    pub fn edges(&self) -> impl Iterator<Item = Segment> + '_ {
        let n = self.vertices.len();
        (0..n).map(move |i| Segment::new(self.vertices[i], self.vertices[(i + 1) % n]))
    }

    pub fn aabb(&self) -> Aabb {
        let mut b = Aabb::empty();
        for v in &self.vertices {
            b.grow(*v);
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rem_pi_is_rem_euclid() {
        let special = [
            0.0,
            -0.0,
            std::f64::consts::PI,
            -std::f64::consts::PI,
            std::f64::consts::PI.next_down(),
            (-std::f64::consts::PI).next_up(),
            1e-300,
            -1e-300,
            7.5,
            -7.5,
            f64::INFINITY,
            f64::NAN,
        ];
        let sweep = (-2000..=2000).map(|k| k as f64 * 0.0037);
        for x in special.into_iter().chain(sweep) {
            assert_eq!(
                rem_pi(x).to_bits(),
                x.rem_euclid(std::f64::consts::PI).to_bits(),
                "{x}"
            );
        }
    }

    #[test]
    fn fast_floor_is_floor_bit_for_bit() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.5,
            2.999_999_999_999_999_6,
            -2.000_000_000_000_000_4,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            2_147_483_647.5,
            -2_147_483_648.5,
            -2_147_483_649.0,
        ];
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..100_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            let bits = state >> 12;
            let scale = [1e-3, 1.0, 1e3, 1e9, 1e17][(state % 5) as usize];
            xs.push((bits as f64 / (1u64 << 52) as f64 - 0.5) * scale);
        }
        for x in xs {
            assert_eq!(floor_f64(x).to_bits(), x.floor().to_bits(), "{x:e}");
            assert_eq!(floor_i32(x), x.floor() as i32, "{x:e}");
        }
    }

    #[test]
    fn pose_between_inverts_compose() {
        let a = Pose::new(1.0, 2.0, 0.7);
        let d = Pose::new(0.3, -0.2, -1.1);
        let b = a.compose(&d);
        let d2 = a.between(&b);
        assert!((d2.x_m - d.x_m).abs() < 1e-12);
        assert!((d2.y_m - d.y_m).abs() < 1e-12);
        assert!((d2.theta_rad - d.theta_rad).abs() < 1e-12);
    }

    #[test]
    fn polygon_area_and_contains() {
        let p = Polygon::rect(Vec2::new(0.0, 0.0), Vec2::new(2.0, 3.0));
        assert_eq!(p.area_m2(), 6.0);
        assert!(p.contains(Vec2::new(1.0, 1.0)));
        assert!(!p.contains(Vec2::new(3.0, 1.0)));
        let w = Polygon::thick_segment(Vec2::new(0.0, 0.0), Vec2::new(4.0, 0.0), 0.2);
        assert!((w.area_m2() - 4.2 * 0.2).abs() < 1e-9);
    }

    #[test]
    fn wrap_angle_range() {
        for k in -20..20 {
            let a = wrap_angle(k as f64 * 0.9);
            assert!(a > -std::f64::consts::PI && a <= std::f64::consts::PI);
        }
    }
}
