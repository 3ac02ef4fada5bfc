//! RGB888 images and PNG input/output: [`tilerast_png::Image`], whose
//! errors convert into the simulator's ([`crate::Error::Io`],
//! [`crate::Error::Png`]).

pub use tilerast_png::Image;

impl From<tilerast_png::Error> for crate::Error {
    fn from(e: tilerast_png::Error) -> Self {
        match e {
            tilerast_png::Error::Io { path, source } => crate::Error::Io { path, source },
            tilerast_png::Error::Png { path, message } => crate::Error::Png { path, message },
            other => crate::Error::Unsupported(other.to_string()),
        }
    }
}
