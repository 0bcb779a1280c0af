//! What a rescue world holds besides walls: victims, dark areas and rough floor.
//!
//! World files declare them (`V` cells and `# dark:`/`# rough:` headers in ASCII worlds;
//! `victims:`, `dark:` and `rough:` keys in map_server YAML); the simulator's camera renders
//! victims and darkens dark areas, and rough floor shakes the robot's sensors.

use petrel_actors::Point2;

/// An axis-aligned rectangle in world coordinates, metres (`x0 < x1`, `y0 < y1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// Left edge.
    pub x0: f64,
    /// Bottom edge.
    pub y0: f64,
    /// Right edge.
    pub x1: f64,
    /// Top edge.
    pub y1: f64,
}

impl Rect {
    /// A rectangle from `[x0, y0, x1, y1]`, or why those numbers are not one.
    pub fn from_corners(c: [f64; 4]) -> Result<Rect, String> {
        let [x0, y0, x1, y1] = c;
        if !c.iter().all(|v| v.is_finite()) {
            return Err(format!("expected finite numbers, got {c:?}"));
        }
        if x0 >= x1 || y0 >= y1 {
            return Err(format!(
                "expected x0 < x1 and y0 < y1 (lower-left then upper-right corner), got [{x0}, {y0}, {x1}, {y1}]"
            ));
        }
        Ok(Rect { x0, y0, x1, y1 })
    }

    /// Whether `(x, y)` lies inside (edges included).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        (self.x0..=self.x1).contains(&x) && (self.y0..=self.y1).contains(&y)
    }

    /// Area, square metres.
    pub fn area(&self) -> f64 {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }
}

/// Victims and special floor areas of a world; all empty in a plain navigation world.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct WorldFeatures {
    /// Victim positions, metres, map frame.
    pub victims: Vec<Point2>,
    /// Dark areas: the camera sees little light there.
    pub dark: Vec<Rect>,
    /// Rough floor: the robot shakes there.
    pub rough: Vec<Rect>,
}

impl WorldFeatures {
    /// Whether `(x, y)` is inside a dark area.
    pub fn is_dark(&self, x: f64, y: f64) -> bool {
        self.dark.iter().any(|r| r.contains(x, y))
    }

    /// Whether `(x, y)` is on rough floor.
    pub fn is_rough(&self, x: f64, y: f64) -> bool {
        self.rough.iter().any(|r| r.contains(x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangles_need_ordered_finite_corners_and_answer_containment() {
        let r = Rect::from_corners([1.0, 2.0, 3.0, 5.0]).unwrap();
        assert!(r.contains(1.0, 2.0) && r.contains(2.5, 4.9) && !r.contains(3.1, 3.0));
        assert_eq!(r.area(), 6.0);
        assert!(Rect::from_corners([3.0, 2.0, 1.0, 5.0])
            .unwrap_err()
            .contains("x0 < x1"));
        assert!(Rect::from_corners([0.0, 0.0, f64::NAN, 1.0]).is_err());
        let f = WorldFeatures {
            dark: vec![r],
            ..WorldFeatures::default()
        };
        assert!(f.is_dark(2.0, 3.0) && !f.is_dark(0.0, 0.0) && !f.is_rough(2.0, 3.0));
    }
}
