//! The driver's pipeline cache (`wgpu::PipelineCache`, Vulkan's `VkPipelineCache`) kept
//! on disk between runs, so a start (or an edit back to something built before) finds
//! its compiled pipelines instead of compiling them again.
//!
//! The file lives under the user cache folder (`$LIGHTGRAPH_PIPELINE_CACHE_DIR`, else
//! `$XDG_CACHE_HOME/lightgraph`, else `~/.cache/lightgraph`; `LIGHTGRAPH_PIPELINE_CACHE_DIR=off`
//! disables it), one file per adapter named after `wgpu::util::pipeline_cache_key`. It is
//! wgpu's data in an envelope of our own: a magic line, the adapter and driver it was made
//! for, the length and a checksum. A file that is corrupt, truncated or made for another
//! adapter or driver is ignored with a warning (and replaced at the next save); wgpu and
//! the driver validate the data again behind that. Saves write a temporary file and
//! rename it over the old one, so a crash mid-write never leaves half a file.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use thiserror::Error;

const MAGIC: &[u8] = b"lightgraph pipeline cache\n";
const FORMAT: u32 = 1;

/// Why a pipeline cache file was not used (each case is a warning and an empty cache, never
/// a failure).
#[derive(Debug, Error)]
pub enum PipelineCacheFileError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The file does not start with this format's header.
    #[error("not a lightgraph pipeline cache (or an older format)")]
    NotOurs,
    /// The file is cut short or its checksum does not match (what was wrong).
    #[error("truncated or corrupt: {0}")]
    Corrupt(&'static str),
    /// The file was made on another adapter or driver (the key it names).
    #[error("made for another adapter or driver ({0})")]
    Foreign(String),
}

/// FNV-1a, 64 bits: enough to catch a damaged file (not an adversary).
fn checksum(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The file's bytes for `data` made on the adapter and driver `key` names.
pub fn encode(key: &str, data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + key.len() + 48);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT.to_le_bytes());
    out.extend_from_slice(&(key.len() as u32).to_le_bytes());
    out.extend_from_slice(key.as_bytes());
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    out.extend_from_slice(&checksum(data).to_le_bytes());
    out.extend_from_slice(data);
    out
}

/// The key a file's bytes were made for and wgpu's data, if they are whole.
pub fn read_envelope(bytes: &[u8]) -> Result<(String, &[u8]), PipelineCacheFileError> {
    use PipelineCacheFileError::*;
    let rest = bytes.strip_prefix(MAGIC).ok_or(NotOurs)?;
    fn take(rest: &[u8], n: usize) -> Result<(&[u8], &[u8]), PipelineCacheFileError> {
        (rest.len() >= n)
            .then(|| rest.split_at(n))
            .ok_or(Corrupt("ends inside the header"))
    }
    let u32_of = |b: &[u8]| u32::from_le_bytes(b.try_into().unwrap_or_default());
    let u64_of = |b: &[u8]| u64::from_le_bytes(b.try_into().unwrap_or_default());
    let (format, rest) = take(rest, 4)?;
    if u32_of(format) != FORMAT {
        return Err(NotOurs);
    }
    let (key_len, rest) = take(rest, 4)?;
    let (key, rest) = take(rest, u32_of(key_len) as usize)?;
    let (len, rest) = take(rest, 8)?;
    let (sum, data) = take(rest, 8)?;
    if data.len() as u64 != u64_of(len) {
        return Err(Corrupt("length does not match"));
    }
    if checksum(data) != u64_of(sum) {
        return Err(Corrupt("checksum does not match"));
    }
    Ok((String::from_utf8_lossy(key).into_owned(), data))
}

/// wgpu's data from a file's bytes, if they are whole and were made for `key`.
pub fn decode<'a>(key: &str, bytes: &'a [u8]) -> Result<&'a [u8], PipelineCacheFileError> {
    let (file_key, data) = read_envelope(bytes)?;
    if file_key != key {
        return Err(PipelineCacheFileError::Foreign(file_key));
    }
    Ok(data)
}

/// The folder pipeline caches are kept in, or `None` when disabled or there is no home.
pub(crate) fn default_dir() -> Option<PathBuf> {
    let non_empty = |v: &str| std::env::var_os(v).filter(|s| !s.is_empty());
    if let Some(dir) = non_empty("LIGHTGRAPH_PIPELINE_CACHE_DIR") {
        return (dir != "off").then(|| PathBuf::from(dir));
    }
    if let Some(xdg) = non_empty("XDG_CACHE_HOME") {
        return Some(PathBuf::from(xdg).join("lightgraph"));
    }
    non_empty("HOME").map(|home| PathBuf::from(home).join(".cache").join("lightgraph"))
}

/// What opening the cache found on disk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CacheLoad {
    /// No file yet: an empty cache.
    Empty,
    /// The file's data was accepted by wgpu and the driver (`bytes` of it).
    Loaded {
        /// Bytes of pipeline data loaded.
        bytes: usize,
    },
    /// The file was unusable and ignored (the warning says why).
    Ignored(String),
    /// The file was whole and ours, but wgpu or the driver refused its data (another
    /// driver version, say): the cache starts empty.
    Refused(String),
}

/// # Safety
/// `data`, if any, must come from `PipelineCache::get_data` (see
/// `Device::create_pipeline_cache`).
unsafe fn create(
    device: &wgpu::Device,
    data: Option<&[u8]>,
    fallback: bool,
) -> wgpu::PipelineCache {
    // SAFETY: passed on from the caller.
    unsafe {
        device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
            label: Some("lightgraph pipeline cache"),
            data,
            fallback,
        })
    }
}

/// A `wgpu::PipelineCache` backed by a file.
pub struct DiskPipelineCache {
    cache: wgpu::PipelineCache,
    path: PathBuf,
    key: String,
    load: CacheLoad,
    /// The checksum and length of the data on disk, to skip saving what is there.
    on_disk: Mutex<Option<(u64, usize)>>,
}

impl DiskPipelineCache {
    /// Opens the cache for `device` (which must have `Features::PIPELINE_CACHE`) in
    /// `dir`; `None` where wgpu keeps no pipeline cache for the backend.
    pub fn open(device: &wgpu::Device, info: &wgpu::AdapterInfo, dir: &Path) -> Option<Self> {
        let name = wgpu::util::pipeline_cache_key(info)?;
        // wgpu's key names the vendor and device; the driver's version is ours to add
        // (wgpu and the driver check it again, but a file for another driver is replaced).
        let key = format!(
            "{name}|{}|{} {}|wgpu 30",
            info.name, info.driver, info.driver_info
        );
        let path = dir.join(format!("{name}.bin"));
        let mut on_disk = None;
        let (data, load) = match std::fs::read(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => (None, CacheLoad::Empty),
            Err(source) => {
                let e = PipelineCacheFileError::Io {
                    path: path.clone(),
                    source,
                };
                log::warn!("pipeline cache: ignoring {e}");
                (None, CacheLoad::Ignored(e.to_string()))
            }
            Ok(bytes) => match decode(&key, &bytes) {
                Ok(data) => {
                    on_disk = Some((checksum(data), data.len()));
                    (Some(data.to_vec()), CacheLoad::Loaded { bytes: data.len() })
                }
                Err(e) => {
                    let e = format!("{}: {e}", path.display());
                    log::warn!("pipeline cache: ignoring {e}");
                    (None, CacheLoad::Ignored(e))
                }
            },
        };
        let (cache, load) = match data {
            Some(data) => {
                // Without fallback wgpu reports data it would not use, so a refusal is
                // seen (and the cache starts empty) instead of passing silently.
                let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
                // SAFETY: `data` is what `PipelineCache::get_data` returned on an adapter
                // with the same key (our envelope's key and checksum say so); wgpu checks
                // its own header, adapter key and the driver's cache UUID again.
                let cache = unsafe { create(device, Some(&data), false) };
                match pollster::block_on(scope.pop()) {
                    None => (cache, load),
                    Some(e) => {
                        log::warn!("pipeline cache: {}: refused: {e}", path.display());
                        on_disk = None;
                        // SAFETY: no data.
                        let empty = unsafe { create(device, None, true) };
                        (empty, CacheLoad::Refused(e.to_string()))
                    }
                }
            }
            // SAFETY: no data.
            None => (unsafe { create(device, None, true) }, load),
        };
        Some(Self {
            cache,
            path,
            key,
            load,
            on_disk: Mutex::new(on_disk),
        })
    }

    /// The wgpu pipeline cache, to pass to pipeline descriptors.
    pub fn cache(&self) -> &wgpu::PipelineCache {
        &self.cache
    }

    /// The cache file on disk.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// What opening found on disk.
    pub fn load(&self) -> &CacheLoad {
        &self.load
    }

    /// Bytes the cache holds now (what a save would write).
    pub(crate) fn held_bytes(&self) -> usize {
        self.cache.get_data().map_or(0, |d| d.len())
    }

    /// Writes the cache's data if it changed since it was loaded or last saved: to a
    /// temporary file beside it, then renamed over it. Returns the bytes written (0:
    /// nothing new).
    pub fn save(&self) -> Result<usize, PipelineCacheFileError> {
        let Some(data) = self.cache.get_data() else {
            return Ok(0);
        };
        let stamp = (checksum(&data), data.len());
        let mut on_disk = self.on_disk.lock().unwrap_or_else(|e| e.into_inner());
        if *on_disk == Some(stamp) {
            return Ok(0);
        }
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| PipelineCacheFileError::Io { path, source }
        };
        if let Some(dir) = self.path.parent() {
            std::fs::create_dir_all(dir).map_err(io(dir))?;
        }
        // Unique per save: several devices of one process may save at once.
        static SAVES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = SAVES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = self
            .path
            .with_extension(format!("tmp-{}-{n}", std::process::id()));
        let bytes = encode(&self.key, &data);
        let written = std::fs::write(&tmp, &bytes)
            .map_err(io(&tmp))
            .and_then(|()| std::fs::rename(&tmp, &self.path).map_err(io(&self.path)));
        if written.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        written?;
        *on_disk = Some(stamp);
        Ok(bytes.len())
    }

    /// [`save`](Self::save), logging instead of failing: the cache only saves time.
    pub(crate) fn save_or_warn(&self) {
        if let Err(e) = self.save() {
            log::warn!("pipeline cache: not saved: {e}");
        }
    }
}

impl Drop for DiskPipelineCache {
    fn drop(&mut self) {
        self.save_or_warn();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_refuses_damage_and_other_adapters() {
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
        let bytes = encode("vk_10de_2335|driver 580", &data);
        assert_eq!(
            decode("vk_10de_2335|driver 580", &bytes).unwrap(),
            &data[..]
        );
        assert!(matches!(
            decode("vk_10de_2335|driver 581", &bytes),
            Err(PipelineCacheFileError::Foreign(_))
        ));
        // Every truncation and every flipped byte is refused, never accepted or a panic.
        for len in 0..bytes.len() {
            assert!(
                decode("vk_10de_2335|driver 580", &bytes[..len]).is_err(),
                "{len}"
            );
        }
        for i in 0..bytes.len() {
            let mut bad = bytes.clone();
            bad[i] ^= 0x10;
            assert!(decode("vk_10de_2335|driver 580", &bad).is_err(), "byte {i}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(decode("vk_10de_2335|driver 580", &longer).is_err());
        assert!(matches!(
            decode("k", b"PNG garbage"),
            Err(PipelineCacheFileError::NotOurs)
        ));
    }
}
