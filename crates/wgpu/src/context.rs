//! Headless adapter selection and the device shared by every renderer of a process.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Which adapter to use. The defaults come from the environment as in wgpu's examples:
/// `WGPU_BACKEND` (a comma list such as `vulkan` or `vulkan,gl`) and `WGPU_ADAPTER_NAME`
/// (a case-insensitive substring of the adapter's name).
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct AdapterRequest {
    /// Backends to search (`WGPU_BACKEND` syntax); `None` for every compiled-in backend.
    pub backends: Option<String>,
    /// A case-insensitive substring the adapter's name must contain; `None` for any.
    pub name: Option<String>,
}

impl AdapterRequest {
    /// The request the environment describes (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`).
    #[must_use]
    pub fn from_env() -> Self {
        let var = |k: &str| std::env::var(k).ok().filter(|v| !v.trim().is_empty());
        Self {
            backends: var("WGPU_BACKEND"),
            name: var("WGPU_ADAPTER_NAME"),
        }
    }

    /// A request for the adapter whose name contains `name`, on any backend.
    #[must_use]
    pub fn named(name: impl Into<String>) -> Self {
        Self {
            backends: None,
            name: Some(name.into()),
        }
    }
}

/// A device and what the renderer needs to know about its adapter.
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's name, type, driver and backend.
    pub info: wgpu::AdapterInfo,
    /// The device's limits (the adapter's own, not wgpu's conservative defaults).
    pub limits: wgpu::Limits,
    /// Whether compute passes can write timestamps.
    pub timestamps: bool,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f64,
    /// Errors the device reported outside any error scope, drained after each frame.
    pub errors: Arc<Mutex<Vec<String>>>,
}

impl Gpu {
    /// `name (type, backend, driver), timestamp queries`, as `raybench backends` shows it.
    #[must_use]
    pub fn describe(&self) -> String {
        format!(
            "{}, {}",
            describe(&self.info),
            if self.timestamps {
                "GPU time from timestamp queries"
            } else {
                "no timestamp queries: GPU time is wall time around submit and wait"
            }
        )
    }

    /// Takes the errors reported since the last call.
    #[must_use]
    pub fn take_errors(&self) -> Vec<String> {
        std::mem::take(&mut *self.errors.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

/// `name (type, backend, driver)` of an adapter.
#[must_use]
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    let kind = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => "discrete GPU",
        wgpu::DeviceType::IntegratedGpu => "integrated GPU",
        wgpu::DeviceType::VirtualGpu => "virtual GPU",
        wgpu::DeviceType::Cpu => "software, runs on the CPU",
        wgpu::DeviceType::Other => "other",
    };
    let driver = if info.driver_info.is_empty() {
        info.driver.clone()
    } else {
        format!("{} {}", info.driver, info.driver_info)
    };
    format!(
        "{} ({kind}, {:?}, {})",
        info.name,
        info.backend,
        driver.trim()
    )
}

/// Preference among adapter types: real GPUs first, software last.
fn rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

type Cache = Mutex<HashMap<AdapterRequest, Result<Arc<Gpu>, String>>>;

/// The device for `request`, created once per process and shared (tests and the report
/// make many renderers; lavapipe takes a noticeable time to start a device). The outcome
/// is cached too when there is no adapter, so that the reason is reported consistently.
///
/// # Errors
/// Why there is no usable adapter or device.
pub fn gpu(request: &AdapterRequest) -> Result<Arc<Gpu>, String> {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(found) = map.get(request) {
        return found.clone();
    }
    let made = open(request).map(Arc::new);
    map.insert(request.clone(), made.clone());
    made
}

fn open(request: &AdapterRequest) -> Result<Gpu, String> {
    let backends = match &request.backends {
        Some(list) => wgpu::Backends::from_comma_list(list),
        None => wgpu::Backends::all(),
    };
    if backends.is_empty() {
        return Err(format!(
            "WGPU_BACKEND '{}' names no backend (try vulkan, metal, dx12 or gl)",
            request.backends.as_deref().unwrap_or_default()
        ));
    }
    // Headless: no display handle. Flags and backend options from the environment
    // (`WGPU_VALIDATION`, `WGPU_DEBUG`, ...), the backend list from the request.
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends,
        ..wgpu::InstanceDescriptor::new_without_display_handle_from_env()
    });
    let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
    let seen: Vec<String> = adapters.iter().map(|a| describe(&a.get_info())).collect();
    if let Some(name) = &request.name {
        let needle = name.to_lowercase();
        adapters.retain(|a| a.get_info().name.to_lowercase().contains(&needle));
    }
    // The most capable kind first; among equals, the order the driver lists them in.
    adapters.sort_by_key(|a| rank(a.get_info().device_type));
    let Some(adapter) = adapters.into_iter().next() else {
        let which = match &request.name {
            Some(n) => format!("no adapter named like '{n}'"),
            None => "no adapter".to_string(),
        };
        let seen = if seen.is_empty() {
            "none found; on Linux without a GPU install Mesa's software Vulkan driver \
             (Debian: apt install mesa-vulkan-drivers libvulkan1)"
                .to_string()
        } else {
            format!("found: {}", seen.join("; "))
        };
        return Err(format!("{which} ({seen})"));
    };
    let info = adapter.get_info();
    let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
    // The adapter's own limits: storage buffers beyond wgpu's default 128 MiB, for large
    // meshes; the renderer checks its buffers against them.
    let limits = adapter.limits();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("raybench"),
        required_features: features,
        required_limits: limits.clone(),
        ..Default::default()
    }))
    .map_err(|e| format!("{}: cannot open a device: {e}", describe(&info)))?;
    let errors: Arc<Mutex<Vec<String>>> = Arc::default();
    let sink = Arc::clone(&errors);
    // wgpu's default handler panics; a backend error must become a RenderError instead.
    device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
        sink.lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(e.to_string());
    }));
    let timestamp_period = f64::from(queue.get_timestamp_period());
    Ok(Gpu {
        device,
        queue,
        info,
        limits,
        timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
        timestamp_period,
        errors,
    })
}
