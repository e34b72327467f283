use super::pipeline_cache::DiskPipelineCache;
use std::sync::Arc;
use thiserror::Error;

/// Why a GPU device could not be opened or read from.
#[derive(Debug, Error)]
pub enum GpuError {
    /// No adapter was found (no GPU driver wgpu supports); the message is wgpu's.
    #[error("no GPU adapter found (on a machine without a GPU install Mesa's lavapipe: apt-get install mesa-vulkan-drivers): {0}")]
    NoAdapter(String),
    /// The adapter refused the device request.
    #[error("could not open a device on adapter {adapter}: {source}")]
    Device {
        /// The adapter's name.
        adapter: String,
        /// wgpu's error.
        source: wgpu::RequestDeviceError,
    },
    /// Mapping a buffer for readback failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
}

/// Per-pass GPU timestamps, inside and between passes.
const TIMESTAMPS: wgpu::Features =
    wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

/// How to open the device. The default takes every feature the project uses that the
/// adapter offers.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Features left off the device even where the adapter offers them, so the device is
    /// what an adapter without them gives: tests of the fallbacks on lavapipe, and
    /// `render --disable-features`.
    pub disabled_features: wgpu::Features,
    /// Storage buffers a shader stage may bind, where lower than what lightgraph asks
    /// (the adapter's, at most 16): the device a smaller GPU gives (WebGPU's default is
    /// 8), for the tests of the message a pipeline over it gets.
    pub storage_buffers_per_stage: Option<u32>,
}

impl ContextOptions {
    /// Feature names as wgpu spells them (`SHADER_INT64_ATOMIC_MIN_MAX`, any case),
    /// separated by commas, spaces or `|`.
    pub fn parse_features(list: &str) -> Result<wgpu::Features, String> {
        let mut features = wgpu::Features::empty();
        for name in list
            .split([',', '|', ' '])
            .map(str::trim)
            .filter(|n| !n.is_empty())
        {
            features |= wgpu::Features::from_name(&name.to_ascii_uppercase()).ok_or_else(|| {
                format!("'{name}' is not a wgpu feature name (e.g. shader_int64_atomic_min_max)")
            })?;
        }
        Ok(features)
    }
}

/// A headless wgpu device and queue, plus what the adapter can do. Clones share them.
#[derive(Clone)]
pub struct GpuContext {
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// The device every pass records and creates resources on.
    pub device: wgpu::Device,
    /// The queue frames are submitted to.
    pub queue: wgpu::Queue,
    /// Whether per-pass GPU timestamps can be recorded.
    pub has_timestamps: bool,
    /// The driver's pipeline cache, kept on disk between runs (Vulkan adapters offering
    /// `Features::PIPELINE_CACHE`, unless `LIGHTGRAPH_PIPELINE_CACHE_DIR=off`). Saved when
    /// the last handle goes and after hot reloads that built pipelines.
    pub pipeline_cache: Option<Arc<DiskPipelineCache>>,
    /// Features the adapter offers that the device was opened without, on request
    /// ([`ContextOptions::disabled_features`]) or by the caller who made the device
    /// ([`Self::from_device`]): passes that fall back say so.
    pub disabled_features: wgpu::Features,
    /// What the adapter's driver cannot do beyond wgpu's limits (a loop's iterations),
    /// from its adapter info; passes check against this, never the adapter's name.
    pub driver_limits: super::DriverLimits,
}

impl GpuContext {
    /// Opens the first adapter wgpu finds (Vulkan), without a window.
    pub fn new_headless() -> Result<Self, GpuError> {
        Self::headless_with(&ContextOptions::default())
    }

    /// [`Self::new_headless`] with `options` (features left off).
    pub fn headless_with(options: &ContextOptions) -> Result<Self, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        pollster::block_on(Self::open(&wgpu::Instance::new(desc), None, options))
    }

    /// Opens an adapter that can present to `surface` (the viewer's window).
    pub fn for_surface(
        instance: &wgpu::Instance,
        surface: &wgpu::Surface<'_>,
    ) -> Result<Self, GpuError> {
        pollster::block_on(Self::open(
            instance,
            Some(surface),
            &ContextOptions::default(),
        ))
    }

    /// A context on the caller's device (see [`crate::render::Renderer::from_device`]):
    /// the features lightgraph would use that the adapter offers but `device` was opened
    /// without count as disabled, so the passes that need them fall back and say so.
    /// The driver's pipeline cache stays off (it belongs to whoever made the device).
    pub fn from_device(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        let disabled_features = (adapter.features() & Self::wanted_features()) - device.features();
        Self {
            has_timestamps: device.features().contains(TIMESTAMPS),
            driver_limits: super::DriverLimits::of(&adapter.get_info()),
            adapter,
            device,
            queue,
            pipeline_cache: None,
            disabled_features,
        }
    }

    /// The features lightgraph takes where the adapter offers them; each has a fallback.
    pub fn wanted_features() -> wgpu::Features {
        // MSAA of Rgba32Float targets and sample counts past 4 are the adapter's to
        // grant (not guaranteed by WebGPU); blending transparent surfaces into them
        // needs FLOAT32_BLENDABLE. Taken where offered; passes that need them say so.
        // The visibility buffer's prepass writes triangle ids (PRIMITIVE_INDEX); the
        // compute rasterizer resolves depth with 64-bit atomic min (SHADER_INT64 and
        // SHADER_INT64_ATOMIC_MIN_MAX). Where missing, those passes say so.
        TIMESTAMPS
            | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
            | wgpu::Features::FLOAT32_BLENDABLE
            | wgpu::Features::PRIMITIVE_INDEX
            | wgpu::Features::SHADER_INT64
            | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX
            // Light culling finds a tile's depth range by subgroup reductions where offered.
            | wgpu::Features::SUBGROUP
            // Compiled pipelines kept on disk between runs (see `pipeline_cache`).
            | wgpu::Features::PIPELINE_CACHE
    }

    /// The limits lightgraph asks of `adapter`: WebGPU's defaults, raised to the
    /// adapter's own where a pass can use more.
    pub fn wanted_limits(adapter: &wgpu::Adapter) -> wgpu::Limits {
        let adapter_limits = adapter.limits();
        wgpu::Limits {
            max_storage_buffer_binding_size: adapter_limits.max_storage_buffer_binding_size,
            max_buffer_size: adapter_limits.max_buffer_size,
            max_storage_buffers_per_shader_stage: adapter_limits
                .max_storage_buffers_per_shader_stage
                .min(16),
            max_compute_workgroup_storage_size: adapter_limits.max_compute_workgroup_storage_size,
            // A G-buffer with geometric normals for ray-cast shadows has three Rgba32Float
            // targets (48 bytes a sample; the default allows 32).
            max_color_attachment_bytes_per_sample: adapter_limits
                .max_color_attachment_bytes_per_sample,
            // Shadow atlases up to 16384² (the default allows 8192).
            max_texture_dimension_2d: adapter_limits.max_texture_dimension_2d,
            ..wgpu::Limits::default()
        }
    }

    async fn open(
        instance: &wgpu::Instance,
        compatible_surface: Option<&wgpu::Surface<'_>>,
        options: &ContextOptions,
    ) -> Result<Self, GpuError> {
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let wanted = Self::wanted_features();
        let disabled_features = adapter.features() & wanted & options.disabled_features;
        let features = (adapter.features() & wanted) - disabled_features;
        let has_timestamps = features.contains(TIMESTAMPS);
        let mut limits = Self::wanted_limits(&adapter);
        if let Some(n) = options.storage_buffers_per_stage {
            limits.max_storage_buffers_per_shader_stage =
                limits.max_storage_buffers_per_shader_stage.min(n);
        }
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("lightgraph"),
                required_features: features,
                required_limits: limits,
                ..Default::default()
            })
            .await
            .map_err(|source| GpuError::Device {
                adapter: adapter.get_info().name,
                source,
            })?;
        let pipeline_cache = features
            .contains(wgpu::Features::PIPELINE_CACHE)
            .then(super::pipeline_cache::default_dir)
            .flatten()
            .and_then(|dir| DiskPipelineCache::open(&device, &adapter.get_info(), &dir))
            .map(Arc::new);
        Ok(Self {
            driver_limits: super::DriverLimits::of(&adapter.get_info()),
            adapter,
            device,
            queue,
            has_timestamps,
            pipeline_cache,
            disabled_features,
        })
    }

    /// Whether the adapter runs on the CPU (lavapipe, llvmpipe, SwiftShader): callers pick
    /// smaller default workloads there.
    pub fn is_software(&self) -> bool {
        self.adapter.get_info().device_type == wgpu::DeviceType::Cpu
    }

    /// The pipeline cache's state in words: where it is and what opening it found.
    pub fn pipeline_cache_status(&self) -> String {
        use super::pipeline_cache::CacheLoad;
        match &self.pipeline_cache {
            None => "off (no PIPELINE_CACHE on this adapter, or disabled)".into(),
            Some(c) => format!(
                "{} ({})",
                c.path().display(),
                match c.load() {
                    CacheLoad::Empty => "no file yet: empty".to_string(),
                    CacheLoad::Loaded { bytes } => format!(
                        "loaded {bytes} bytes, accepted; the driver holds {} after opening",
                        c.held_bytes()
                    ),
                    CacheLoad::Ignored(why) => format!("ignored: {why}"),
                    CacheLoad::Refused(why) => format!("refused by wgpu or the driver: {why}"),
                }
            ),
        }
    }

    /// "NVIDIA H200 (Vulkan)" or "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)".
    pub fn adapter_name(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?})", info.name, info.backend)
    }
}

#[cfg(test)]
mod tests {
    use super::ContextOptions;

    #[test]
    fn parses_feature_names_in_any_case() {
        let f =
            ContextOptions::parse_features("shader_int64_atomic_min_max, SHADER_INT64").unwrap();
        assert_eq!(
            f,
            wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX | wgpu::Features::SHADER_INT64
        );
        assert_eq!(
            ContextOptions::parse_features("").unwrap(),
            wgpu::Features::empty()
        );
        let e = ContextOptions::parse_features("shader_int64|nope").unwrap_err();
        assert!(e.contains("'nope' is not a wgpu feature name"), "{e}");
    }
}
