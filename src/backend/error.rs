use ash::vk;

/// Errors of the Vulkan backend. Capability gaps are [`BackendError::Unsupported`], never panics.
#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    #[error("Vulkan loader not found ({0}); install the Vulkan loader and a driver, e.g. `apt-get install libvulkan1 mesa-vulkan-drivers`")]
    Loader(String),
    #[error("{call} failed: {result}")]
    Vulkan { call: &'static str, result: vk::Result },
    #[error("unsupported: {0}")]
    Unsupported(String),
    #[error("no Vulkan device{0}")]
    NoDevice(String),
    #[error("GPU memory allocation for `{name}` failed: {message}")]
    Allocation { name: String, message: String },
    #[error("shader `{name}`: {message}")]
    Shader { name: String, message: String },
    #[error("pipeline `{pipeline}`: binding `{binding}`: {message}")]
    Binding { pipeline: String, binding: String, message: String },
    #[error("{0}")]
    Invalid(String),
}

pub type BackendResult<T> = Result<T, BackendError>;

/// Attaches the name of the Vulkan call to a raw `vk::Result`.
pub(crate) trait VkContext<T> {
    fn vk(self, call: &'static str) -> BackendResult<T>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> BackendResult<T> {
        self.map_err(|result| BackendError::Vulkan { call, result })
    }
}
