//! A test's own directory under the system temp dir, removed when the test is done with it,
//! passed or failed. Set `PENUMBRA_KEEP_TEST_FILES` to keep it and look at what a test wrote.
//!
//! The library's unit tests use it as `crate::util::test_files`; the integration tests include
//! this same file from `tests/support`.

use std::path::{Path, PathBuf};

/// An empty directory made for one test; dropping it removes it with what is in it.
pub struct TestDir(PathBuf);

impl TestDir {
    /// `penumbra-test-<process>-<name>` in the temp dir, emptied if a run before left it.
    pub fn new(name: &str) -> TestDir {
        let dir = std::env::temp_dir().join(format!("penumbra-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("make a test's temp dir");
        TestDir(dir)
    }
}

impl std::ops::Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if std::env::var_os("PENUMBRA_KEEP_TEST_FILES").is_some() {
            eprintln!("test files kept in {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
