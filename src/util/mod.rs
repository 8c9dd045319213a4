//! Utilities that know nothing of scenes or lighting: console output that survives a closed
//! stream, the progress line, CPU parallelism, the backend's GPU pass timings summarised over
//! frames, and image files (PNG, EXR, HDR).

pub mod console;
pub mod image_io;
pub(crate) mod parallel;
pub mod progress;
#[cfg(test)]
pub(crate) mod test_files;
pub mod timing;
