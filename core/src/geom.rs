//! Integer rectangles in screen pixels.

/// An axis-aligned rectangle of whole pixels: `x..x+w`, `y..y+h`.
///
/// ```
/// use tilerast::geom::Rect;
/// let a = Rect::new(0, 0, 10, 10);
/// assert_eq!(a.intersect(&Rect::new(5, -5, 10, 10)), Some(Rect::new(5, 0, 5, 5)));
/// assert_eq!(a.intersect(&Rect::new(10, 0, 1, 1)), None);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rect {
    /// Left column.
    pub x: i32,
    /// Top row.
    pub y: i32,
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
}

impl Rect {
    /// A rectangle from its top-left corner and size.
    pub const fn new(x: i32, y: i32, w: u32, h: u32) -> Self {
        Rect { x, y, w, h }
    }

    /// One past the right column (computed in `i64`: never overflows).
    pub fn x1(&self) -> i64 {
        self.x as i64 + self.w as i64
    }

    /// One past the bottom row.
    pub fn y1(&self) -> i64 {
        self.y as i64 + self.h as i64
    }

    /// The overlap of two rectangles, `None` when empty.
    pub fn intersect(&self, o: &Rect) -> Option<Rect> {
        let x0 = (self.x as i64).max(o.x as i64);
        let y0 = (self.y as i64).max(o.y as i64);
        let x1 = self.x1().min(o.x1());
        let y1 = self.y1().min(o.y1());
        if x0 < x1 && y0 < y1 {
            Some(Rect::new(
                x0 as i32,
                y0 as i32,
                (x1 - x0) as u32,
                (y1 - y0) as u32,
            ))
        } else {
            None
        }
    }

    /// Number of pixels.
    pub fn area(&self) -> u64 {
        self.w as u64 * self.h as u64
    }
}

/// Rectangles convert to and from `embedded-graphics`' `Rectangle`.
///
/// ```
/// use tilerast::prelude::*;
/// use embedded_graphics_core::{geometry::{Point, Size}, primitives::Rectangle};
/// let r = Rectangle::new(Point::new(-2, 3), Size::new(10, 4));
/// assert_eq!(Rect::from(r), Rect::new(-2, 3, 10, 4));
/// assert_eq!(Rectangle::from(Rect::new(-2, 3, 10, 4)), r);
/// ```
impl From<embedded_graphics_core::primitives::Rectangle> for Rect {
    fn from(r: embedded_graphics_core::primitives::Rectangle) -> Self {
        Rect::new(r.top_left.x, r.top_left.y, r.size.width, r.size.height)
    }
}

impl From<Rect> for embedded_graphics_core::primitives::Rectangle {
    fn from(r: Rect) -> Self {
        use embedded_graphics_core::geometry::{Point, Size};
        embedded_graphics_core::primitives::Rectangle::new(
            Point::new(r.x, r.y),
            Size::new(r.w, r.h),
        )
    }
}
