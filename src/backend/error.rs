use ash::vk;

/// Errors of the Vulkan backend. Capability gaps are [`BackendError::Unsupported`], never panics.
#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    #[error("Vulkan loader not found ({0}); install the Vulkan loader and a driver, e.g. `apt-get install libvulkan1 mesa-vulkan-drivers`")]
    Loader(String),
    #[error("{call} failed: {result}")]
    Vulkan { call: &'static str, result: vk::Result },
    /// The driver lost the device (a GPU reset, a driver crash, a hung submission): nothing it
    /// held can be used again.
    #[error("the GPU device was lost during {call} (driver reset or crash); nothing was written by this step, run the command again")]
    DeviceLost { call: &'static str },
    /// Device or host memory ran out in a Vulkan call.
    #[error("{call}: out of {which} memory; try a smaller --size or fewer lights, or close other GPU programs")]
    OutOfMemory { call: &'static str, which: &'static str },
    #[error("unsupported: {0}")]
    Unsupported(String),
    #[error("no Vulkan device{0}")]
    NoDevice(String),
    #[error("GPU memory allocation for `{name}` failed: {message}")]
    Allocation { name: String, message: String },
    #[error("shader `{name}`: {message}")]
    Shader { name: String, message: String },
    #[error("pipeline `{pipeline}`: binding `{binding}`: {message}")]
    Binding {
        pipeline: String,
        binding: String,
        message: String,
    },
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
        self.map_err(|result| BackendError::from_vk(call, result))
    }
}

impl BackendError {
    /// A failed Vulkan call, with the results a user can meet at any time (device loss, memory
    /// exhaustion) given their own variants and sentences.
    pub fn from_vk(call: &'static str, result: vk::Result) -> BackendError {
        match result {
            vk::Result::ERROR_DEVICE_LOST => BackendError::DeviceLost { call },
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => BackendError::OutOfMemory { call, which: "GPU" },
            vk::Result::ERROR_OUT_OF_HOST_MEMORY => BackendError::OutOfMemory { call, which: "host" },
            _ => BackendError::Vulkan { call, result },
        }
    }
}

/// Test hook: `PENUMBRA_INJECT_FAULT=device-lost` makes queue submissions report a lost device,
/// so that the path a real device loss takes can be exercised on any machine.
pub(crate) fn injected_submit_fault() -> Option<vk::Result> {
    match std::env::var("PENUMBRA_INJECT_FAULT").as_deref() {
        Ok("device-lost") => Some(vk::Result::ERROR_DEVICE_LOST),
        Ok("out-of-memory") => Some(vk::Result::ERROR_OUT_OF_DEVICE_MEMORY),
        _ => None,
    }
}
