//! Errors are values: nothing in the core panics on user input.

/// What can go wrong when building or drawing commands.
///
/// ```
/// use tilerast::prelude::*;
/// let mut list: DisplayList<1> = DisplayList::new();
/// let fill = Command::fill(Rect::new(0, 0, 4, 4), Rgb::new(1, 2, 3));
/// assert!(list.push(fill).is_ok());
/// assert_eq!(list.push(fill), Err(Error::ListFull));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// The display list is at capacity.
    ListFull,
    /// A coordinate lies outside `[-COORD_LIMIT, COORD_LIMIT)`.
    CoordOutOfRange,
    /// A float input was NaN or infinite.
    NotFinite,
    /// A span's interpolated values leave their range before its last pixel.
    SpanOutOfRange,
    /// A screen or tile size is zero or larger than `MAX_SIDE`.
    BadSize,
    /// The tile rectangle holds more pixels than the tile's capacity.
    TileTooLarge,
    /// An output buffer is too small for the encoded data.
    BufferTooSmall,
    /// Encoded input is truncated or has an unknown tag or version.
    Malformed,
    /// A scene's configuration does not match the tile types it is rendered
    /// with, or a command's kind is one the tile's
    /// [`CommandSet`](crate::config::CommandSet) leaves out.
    ConfigMismatch,
    /// A degenerate camera, projection, viewport or direction (a zero
    /// field of view, `near >= far`, `eye == target`, a zero vector, or a
    /// non-finite matrix).
    Degenerate,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Error::ListFull => "display list is full",
            Error::CoordOutOfRange => "coordinate outside the documented range",
            Error::NotFinite => "NaN or infinite input",
            Error::SpanOutOfRange => "span values leave their range",
            Error::BadSize => "screen or tile size is zero or too large",
            Error::TileTooLarge => "tile rectangle exceeds tile capacity",
            Error::BufferTooSmall => "output buffer too small",
            Error::Malformed => "malformed encoded data",
            Error::ConfigMismatch => {
                "scene configuration (or a command kind) does not match the tile types"
            }
            Error::Degenerate => "degenerate camera, projection, viewport or direction",
        })
    }
}

impl core::error::Error for Error {}

/// Error from rendering a frame into a display: the raster core's or the
/// display's own.
///
/// ```
/// use tilerast::prelude::*;
/// let e: FlushError<core::convert::Infallible> = Error::TileTooLarge.into();
/// assert_eq!(e.to_string(), "raster: tile rectangle exceeds tile capacity");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FlushError<E> {
    /// The raster core rejected a command or the configuration.
    Raster(Error),
    /// The `DrawTarget` failed.
    Target(E),
}

impl<E> From<Error> for FlushError<E> {
    fn from(e: Error) -> Self {
        FlushError::Raster(e)
    }
}

impl<E: core::fmt::Debug> core::fmt::Display for FlushError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FlushError::Raster(e) => write!(f, "raster: {e}"),
            FlushError::Target(e) => write!(f, "display: {e:?}"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for FlushError<E> {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            FlushError::Raster(e) => Some(e),
            FlushError::Target(_) => None,
        }
    }
}

/// A display that cannot fail leaves only the raster core's error, so `?`
/// converts.
///
/// ```
/// use tilerast::prelude::*;
/// fn render() -> Result<(), Error> {
///     let e: FlushError<core::convert::Infallible> = Error::BadSize.into();
///     Err(e)?
/// }
/// assert_eq!(render(), Err(Error::BadSize));
/// ```
impl From<FlushError<core::convert::Infallible>> for Error {
    fn from(e: FlushError<core::convert::Infallible>) -> Self {
        match e {
            FlushError::Raster(e) => e,
            FlushError::Target(never) => match never {},
        }
    }
}
