//! The bake stage: precomputation (light-maps, SH transfer, per-light vertex colours, visibility
//! tables) through one mechanism.
//!
//! A bake is named and keyed by everything it depends on ([`BakeKey`]: geometry, materials, the
//! lights it bakes, parameters, the SPIR-V of the shaders it runs). Its result is cached on disk
//! under `.penumbra-cache/bake/` (or `$PENUMBRA_CACHE/bake/`), written to a temporary file and
//! renamed so a crash mid-write never leaves a file that looks complete (the first bake that
//! writes removes temporaries whose writer is gone, so a killed run's never pile up). A file is checked on
//! the way in (magic, key, length, checksum, decoding): a corrupt or truncated one is rebuilt
//! with a one-line warning. Every bake's time, size and whether it came from the cache are
//! reported ([`BakeReport`]) apart from frame time, for `profile`, `chart` and `penumbra bake`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::error::{Error, Result};
pub use crate::util::progress::Progress;

pub(crate) mod gpu_loop;

/// FNV-1a: a stable content hash (std's hasher may change between releases).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Everything a bake depends on, as text that is hashed into the cache file's name.
#[derive(Clone, Debug, Default)]
pub struct BakeKey {
    text: String,
}

impl BakeKey {
    pub fn new(name: &str) -> BakeKey {
        BakeKey {
            text: format!("bake:{name}"),
        }
    }

    /// Adds an input by its `Debug` form (parameters, scene values).
    pub fn with(mut self, label: &str, value: impl std::fmt::Debug) -> BakeKey {
        let _ = write!(self.text, "|{label}={value:?}");
        self
    }

    /// Adds raw bytes by their hash (geometry, images).
    pub fn with_bytes(mut self, label: &str, bytes: &[u8]) -> BakeKey {
        let _ = write!(self.text, "|{label}#{:016x}", fnv1a(bytes));
        self
    }

    /// Adds the embedded SPIR-V of every shader whose name starts with `prefix`.
    pub fn with_shaders(mut self, prefix: &str) -> BakeKey {
        for (name, spirv) in crate::shaders::ShaderLibrary::embedded_names().zip(crate::shaders::embedded_bytes()) {
            if name.starts_with(prefix) {
                let _ = write!(self.text, "|{name}:{:016x}", fnv1a(spirv));
            }
        }
        self
    }

    pub fn hash(&self) -> u64 {
        fnv1a(self.text.as_bytes())
    }
}

/// A bake's result as bytes on disk. `decode` returns `None` for anything it cannot read back
/// exactly (the cache then rebuilds).
pub trait BakeData: Sized {
    fn encode(&self) -> Vec<u8>;
    fn decode(bytes: &[u8]) -> Option<Self>;
}

impl BakeData for Vec<f64> {
    fn encode(&self) -> Vec<u8> {
        self.iter().flat_map(|v| v.to_le_bytes()).collect()
    }
    fn decode(bytes: &[u8]) -> Option<Self> {
        bytes.len().is_multiple_of(8).then(|| {
            bytes
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8-byte chunk")))
                .collect()
        })
    }
}

impl BakeData for Vec<f32> {
    fn encode(&self) -> Vec<u8> {
        self.iter().flat_map(|v| v.to_le_bytes()).collect()
    }
    fn decode(bytes: &[u8]) -> Option<Self> {
        bytes.len().is_multiple_of(4).then(|| {
            bytes
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes(c.try_into().expect("4-byte chunk")))
                .collect()
        })
    }
}

/// How one bake went.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BakeReport {
    pub name: String,
    /// The key's hash (the cache file's name).
    pub key: String,
    /// Wall time to build, or to read and check the cached file.
    pub ms: f64,
    /// Size of the result.
    pub bytes: u64,
    pub cached: bool,
    /// Why a cached file was not used, when there was one.
    pub rebuilt: Option<String>,
    /// Why a built result could not be stored in the cache, when it could not.
    pub not_stored: Option<String>,
}

/// Runs bakes through the cache and keeps their reports.
#[derive(Debug)]
pub struct Baker {
    dir: Option<PathBuf>,
    reports: Vec<BakeReport>,
    /// The cache directory was swept of temporaries that killed runs left behind.
    swept: bool,
    /// Only results already in the cache are used: a bake that would run fails instead.
    cached_only: bool,
    /// The first bake refused for that reason.
    missing: Option<String>,
}

const MAGIC: &[u8; 8] = b"PNBAKE01";
const HEADER: usize = 8 + 8 + 8 + 8;

impl Baker {
    /// A baker caching in `dir` (`None`: no cache, every bake runs).
    pub fn new(dir: Option<PathBuf>) -> Baker {
        Baker {
            dir,
            reports: Vec::new(),
            swept: false,
            cached_only: false,
            missing: None,
        }
    }

    /// A baker that only reads `dir`: a bake not cached there fails, and [`Baker::missing`]
    /// names it (the demo then runs it on another thread while its frames go on).
    pub fn cached_only(dir: PathBuf) -> Baker {
        Baker {
            cached_only: true,
            ..Baker::new(Some(dir))
        }
    }

    /// The bake a cache-only baker refused to run.
    pub fn missing(&self) -> Option<&str> {
        self.missing.as_deref()
    }

    /// `$PENUMBRA_CACHE/bake`, or `.penumbra-cache/bake` in the working directory.
    pub fn default_dir() -> PathBuf {
        std::env::var_os("PENUMBRA_CACHE")
            .map_or_else(|| PathBuf::from(".penumbra-cache"), PathBuf::from)
            .join("bake")
    }

    pub fn reports(&self) -> &[BakeReport] {
        &self.reports
    }

    pub fn take_reports(&mut self) -> Vec<BakeReport> {
        std::mem::take(&mut self.reports)
    }

    /// The file a key is cached in.
    pub fn path(&self, name: &str, key: &BakeKey) -> Option<PathBuf> {
        let safe: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        self.dir
            .as_ref()
            .map(|d| d.join(format!("{safe}-{:016x}.bin", key.hash())))
    }

    /// The result of bake `name` for `key`: read from the cache, or built by `build` (given a
    /// progress reporter) and cached.
    pub fn bake<T: BakeData>(
        &mut self,
        name: &str,
        key: &BakeKey,
        build: impl FnOnce(&mut Progress) -> Result<T>,
    ) -> Result<T> {
        let start = Instant::now();
        let path = self.path(name, key);
        let mut rebuilt = None;
        if let Some(p) = &path {
            match read_cached::<T>(p, key.hash()) {
                Ok(Some((value, bytes))) => {
                    self.reports.push(BakeReport {
                        name: name.into(),
                        key: format!("{:016x}", key.hash()),
                        ms: ms_since(start),
                        bytes,
                        cached: true,
                        rebuilt: None,
                        not_stored: None,
                    });
                    return Ok(value);
                }
                Ok(None) => {}
                Err(why) => {
                    crate::errln!(
                        "warning: {}: bake cache unusable ({why}); rebuilding {name}",
                        p.display()
                    );
                    rebuilt = Some(why);
                }
            }
        }
        if self.cached_only {
            self.missing = Some(name.to_string());
            return Err(Error::Usage(format!("{name}: not in the bake cache")));
        }
        if crate::util::progress::this_thread_cancelled() {
            return Err(Error::Cancelled(name.to_string()));
        }
        let mut progress = Progress::new(name);
        let value = build(&mut progress)?;
        progress.finish();
        // A build that stopped early when asked to returns what it had: never cached.
        check_cancelled(&progress, name)?;
        let payload = value.encode();
        let mut not_stored = None;
        if let Some(p) = &path {
            if !self.swept {
                self.swept = true;
                if let Some(dir) = p.parent() {
                    remove_stale_temporaries(dir);
                }
            }
            // A cache that cannot be written costs the next run a rebuild, nothing else here
            // (`penumbra bake`, whose whole point is storing, fails on it).
            if let Err(e) = write_cached(p, key.hash(), &payload) {
                crate::errln!("warning: {}: cannot write the bake cache: {e}", p.display());
                not_stored = Some(format!("{}: {e}", p.display()));
            }
        }
        self.reports.push(BakeReport {
            name: name.into(),
            key: format!("{:016x}", key.hash()),
            ms: ms_since(start),
            bytes: payload.len() as u64,
            cached: false,
            rebuilt,
            not_stored,
        });
        Ok(value)
    }
}

/// `Err(Cancelled)` once the work `progress` follows was asked to stop: long bakes call this
/// between batches (GPU submissions, chunks of a parallel loop) and return the error.
pub fn check_cancelled(progress: &Progress, what: &str) -> Result<()> {
    if progress.cancelled() {
        return Err(Error::Cancelled(what.to_string()));
    }
    Ok(())
}

fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// `Ok(None)`: no file. `Err(why)`: a file that is not a valid entry for `key`.
fn read_cached<T: BakeData>(path: &Path, key: u64) -> std::result::Result<Option<(T, u64)>, String> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot read: {e}")),
    };
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return Err("not a penumbra bake file".into());
    }
    let word = |i: usize| u64::from_le_bytes(bytes[8 + 8 * i..16 + 8 * i].try_into().expect("8 bytes"));
    if word(0) != key {
        return Err("written for another key".into());
    }
    let payload = &bytes[HEADER..];
    if word(1) != payload.len() as u64 {
        return Err(format!("truncated: {} of {} bytes", payload.len(), word(1)));
    }
    if word(2) != fnv1a(payload) {
        return Err("checksum mismatch".into());
    }
    T::decode(payload)
        .map(|v| Some((v, payload.len() as u64)))
        .ok_or_else(|| "cannot decode".to_string())
}

fn write_cached(path: &Path, key: u64, payload: &[u8]) -> std::io::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let mut bytes = Vec::with_capacity(HEADER + payload.len());
    bytes.extend_from_slice(MAGIC);
    for w in [key, payload.len() as u64, fnv1a(payload)] {
        bytes.extend_from_slice(&w.to_le_bytes());
    }
    bytes.extend_from_slice(payload);
    // Unique per process and call: two threads baking the same key never share a temporary.
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_extension(format!("{TEMPORARY}{}-{n}", std::process::id()));
    let written = std::fs::write(&tmp, &bytes).and_then(|()| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// A temporary's extension: this, the writer's process id, `-`, a counter.
const TEMPORARY: &str = "tmp";

/// Removes the temporaries in `dir` whose writer is gone (a run killed while writing): on Linux
/// those of processes that no longer exist, elsewhere those over a day old. A live writer's are
/// left alone, so two runs sharing a cache never delete each other's files.
fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let proc = Path::new("/proc/self").exists();
    for entry in entries.flatten() {
        let path = entry.path();
        let Some(pid) = path
            .extension()
            .and_then(|e| e.to_str())
            .and_then(|e| e.strip_prefix(TEMPORARY))
            .and_then(|e| e.split('-').next())
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        let gone = if proc {
            pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists()
        } else {
            entry
                .metadata()
                .and_then(|m| m.modified())
                .is_ok_and(|t| t.elapsed().is_ok_and(|age| age.as_secs() > 86_400))
        };
        if gone {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// Prints bake reports as a table (for `profile` and `penumbra bake`).
pub fn table(reports: &[BakeReport]) -> String {
    if reports.is_empty() {
        return String::new();
    }
    let mut s = format!("{:<48} {:>10} {:>12}  {}\n", "bake", "ms", "bytes", "source");
    for r in reports {
        let source = match (&r.rebuilt, r.cached) {
            _ if r.not_stored.is_some() => "built, NOT stored".to_string(),
            (_, true) => "cache".to_string(),
            (Some(why), false) => format!("built (cache rebuilt: {why})"),
            (None, false) => "built".to_string(),
        };
        s += &format!("{:<48} {:>10.3} {:>12}  {source}\n", r.name, r.ms, r.bytes);
    }
    s
}

#[cfg(test)]
mod tests;
