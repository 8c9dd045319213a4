//! The crate-level error: every failure a user can cause or meet, printed as one line.

use crate::backend::BackendError;
use crate::scene::SceneError;
use crate::util::image_io::ImageIoError;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Backend(#[from] BackendError),
    #[error(transparent)]
    Image(#[from] ImageIoError),
    #[error(transparent)]
    Metrics(#[from] crate::metrics::MetricsError),
    /// A request that cannot be honoured as asked (a method the scene doesn't enable, a size of 0…).
    #[error("{0}")]
    Usage(String),
}

pub type Result<T> = std::result::Result<T, Error>;
