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
    /// Long work stopped because it was asked to (the demo's Cancel): the work named.
    #[error("{0}: cancelled")]
    Cancelled(String),
    /// The validation layer reported messages, printed as they came.
    #[error("{0} validation message(s) (see above)")]
    Validation(usize),
    /// A fault inside penumbra, not in what the user gave it: a read-back shorter than what was
    /// written, a pipeline the frame should have made, a cached bake that passed its checks but
    /// does not fit the scene. The context says where.
    #[error("internal error: {0} (a fault in penumbra, not in the input; please report it)")]
    Internal(String),
}

pub type Result<T> = std::result::Result<T, Error>;
