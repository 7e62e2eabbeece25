//! [`WgpuRenderer`]: the frame-level [`Renderer`] on a wgpu device.

use crate::context::{AdapterRequest, Gpu, gpu};
use crate::cwbvh::{self, Cwbvh};
use crate::data::{SceneData, bvh2_nodes, check_kinds, entry_point};
use crate::plan;
use crate::records::{Features, GpuOut, Layout, Params, STACK_SIZE};
use raybench_bvh::Bvh;
use raybench_core::{
    Accel, AccelStats, Frame, FrameStats, Hit, Mode, NO_HIT, QualityParams, Ray, RayCounters,
    RenderError, RenderSettings, Renderer, Scene, StructureQuality, Timings, Vec3,
};
use std::collections::HashMap;
use std::num::NonZeroU64;
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

use crate::constants::kernel_source;

mod rays;

pub use rays::Phased;

/// Compute passes per submission; their timestamps are read back after each submission.
const PASSES_PER_SUBMIT: usize = 64;

/// How long a submission may take before the frame is abandoned with an error (a real GPU
/// finishes a dispatch in milliseconds; lavapipe in seconds).
const WAIT_LIMIT: Duration = Duration::from_secs(600);

/// A pipeline's entry point, whether it counts, the tree it walks, and the scene's
/// [`Features`].
type PipelineKey = (&'static str, bool, Layout, Features);

/// The compiled kernels of one device: one pipeline per (entry point, counting, layout).
pub(crate) struct Kernels {
    module: wgpu::ShaderModule,
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    /// One slot per key, each behind its own lock: a thread compiling one pipeline (a minute
    /// for some on lavapipe) holds only its slot, so other threads compile theirs meanwhile.
    pipelines: Mutex<HashMap<PipelineKey, Arc<PipelineSlot>>>,
}

/// A pipeline once compiled (`None` until then, or after a failed compile).
type PipelineSlot = Mutex<Option<Arc<wgpu::ComputePipeline>>>;

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Fails with the errors the device reported since the last check.
fn device_errors(gpu: &Gpu, what: &str) -> Result<(), RenderError> {
    let errors = gpu.take_errors();
    if errors.is_empty() {
        Ok(())
    } else {
        Err(RenderError::Backend(format!(
            "{what}: {}",
            errors.join("; ")
        )))
    }
}

impl Kernels {
    fn new(gpu: &Gpu) -> Result<Self, RenderError> {
        let d = &gpu.device;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raybench kernels"),
            source: wgpu::ShaderSource::Wgsl(kernel_source().into()),
        });
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: NonZeroU64::new(std::mem::size_of::<Params>() as u64),
            },
            count: None,
        }];
        entries.extend((1..=5).map(|b| storage(b, true)));
        entries.extend((6..=7).map(|b| storage(b, false)));
        entries.extend([storage(8, true), storage(9, true)]);
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raybench bindings"),
            entries: &entries,
        });
        let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("raybench layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        device_errors(gpu, "compiling the WGSL kernels")?;
        Ok(Self {
            module,
            layout,
            pipeline_layout,
            pipelines: Mutex::default(),
        })
    }

    /// The pipeline of `entry`, with or without counting, over the tree of `layout`,
    /// compiled on first use.
    fn pipeline(
        &self,
        gpu: &Gpu,
        entry: &'static str,
        count: bool,
        layout: Layout,
        features: Features,
    ) -> Result<Arc<wgpu::ComputePipeline>, RenderError> {
        let key = (entry, count, layout, features);
        let slot = {
            let mut map = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
            Arc::clone(map.entry(key).or_default())
        };
        let mut slot = slot.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = slot.as_ref() {
            return Ok(Arc::clone(p));
        }
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        let mut constants = vec![
            ("COUNT", flag(count)),
            ("WIDE", flag(layout == Layout::Cwbvh)),
        ];
        constants.extend(features.constants());
        let pipeline = gpu
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&self.pipeline_layout),
                module: &self.module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                },
                cache: None,
            });
        device_errors(gpu, &format!("compiling kernel {entry}"))?;
        let pipeline = Arc::new(pipeline);
        *slot = Some(Arc::clone(&pipeline));
        Ok(pipeline)
    }
}

/// The tree of a prepared scene.
enum Tree {
    Bvh2(Bvh),
    Cwbvh(Cwbvh),
}

/// A renderer prepared for one scene.
struct Prepared {
    gpu: Arc<Gpu>,
    kernels: Arc<Kernels>,
    scene: Arc<Scene>,
    data: SceneData,
    stats: AccelStats,
    /// The tree the buffers were filled from, kept for [`Renderer::quality`].
    tree: Tree,
    nodes: wgpu::Buffer,
    wide: wgpu::Buffer,
    prims: wgpu::Buffer,
    prim_info: wgpu::Buffer,
    shading: wgpu::Buffer,
    /// The primitives' own data (`geo`).
    geo: wgpu::Buffer,
    /// What the scene needs of the kernels.
    features: Features,
    /// One frame at a time: frames share the device's queue and the kernels.
    frame_lock: Mutex<()>,
}

/// The wgpu compute backend: the scene's BVH2 is built on the CPU by raybench-bvh (and,
/// with [`Layout::Cwbvh`], collapsed into a compressed 8-wide BVH), flattened and uploaded
/// once; each frame runs one WGSL kernel per mode over 8 x 8 pixel blocks, in dispatches
/// bounded by [`plan::budget`], and reads the image back. Any-hit rays
/// ([`Renderer::occlude_rays`]) run a kernel of their own that stops at the first hit.
///
/// Results match the CPU backends within floating-point tolerance, not bit for bit (see
/// `kernels/main.wgsl`). Timings of a frame: `upload` (parameters), `gpu` (execution, from
/// timestamp queries when the adapter has them, else wall time around submit and wait),
/// `readback`, and `render` (the whole call).
pub struct WgpuRenderer {
    name: String,
    description: String,
    request: AdapterRequest,
    layout: Layout,
    prepared: Option<Prepared>,
}

/// Compiled kernels per device (keyed by the device's address), so that renderers made one
/// after another compile the WGSL once.
fn kernels(gpu: &Arc<Gpu>) -> Result<Arc<Kernels>, RenderError> {
    type Map = Mutex<HashMap<usize, Arc<Kernels>>>;
    static MAP: std::sync::OnceLock<Map> = std::sync::OnceLock::new();
    let mut map = MAP
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let key = Arc::as_ptr(gpu) as usize;
    if let Some(k) = map.get(&key) {
        return Ok(Arc::clone(k));
    }
    let k = Arc::new(Kernels::new(gpu)?);
    map.insert(key, Arc::clone(&k));
    Ok(k)
}

impl WgpuRenderer {
    /// A renderer on the adapter the environment selects (`WGPU_BACKEND`,
    /// `WGPU_ADAPTER_NAME`; otherwise the most capable adapter found).
    #[must_use]
    pub fn new(name: impl Into<String>, description: impl Into<String>) -> Self {
        Self::with_request(name, description, AdapterRequest::from_env())
    }

    /// A renderer on the adapter `request` selects.
    #[must_use]
    pub fn with_request(
        name: impl Into<String>,
        description: impl Into<String>,
        request: AdapterRequest,
    ) -> Self {
        Self {
            name: name.into(),
            description: description.into(),
            request,
            layout: Layout::Bvh2,
            prepared: None,
        }
    }

    /// The same renderer over the tree of `layout`.
    #[must_use]
    pub fn with_layout(mut self, layout: Layout) -> Self {
        self.layout = layout;
        self.prepared = None;
        self
    }

    /// The tree the kernels walk.
    #[must_use]
    pub fn layout(&self) -> Layout {
        self.layout
    }

    fn gpu(&self) -> Result<Arc<Gpu>, RenderError> {
        gpu(&self.request).map_err(RenderError::Unavailable)
    }

    /// Bytes a storage binding may hold on this device.
    fn binding_limit(gpu: &Gpu) -> u64 {
        gpu.limits
            .max_storage_buffer_binding_size
            .min(gpu.limits.max_buffer_size)
    }
}

fn buffer_init(gpu: &Gpu, label: &str, bytes: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    // wgpu refuses bindings smaller than one element of the shader's array: an empty
    // array gets one zero element of the largest kind (an 80-byte CWBVH node).
    let zeros = [0u8; 80];
    let contents = if bytes.is_empty() { &zeros[..] } else { bytes };
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
}

fn buffer(gpu: &Gpu, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage,
        mapped_at_creation: false,
    })
}

/// Waits for all submitted work, bounded by [`WAIT_LIMIT`].
fn wait(gpu: &Gpu) -> Result<(), RenderError> {
    gpu.device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(WAIT_LIMIT),
        })
        .map(|_| ())
        .map_err(|e| RenderError::Backend(format!("waiting for the GPU: {e}")))
}

/// Maps `staging` (after its copy was submitted), hands its bytes to `read`, unmaps.
fn read_back<T>(
    gpu: &Gpu,
    staging: &wgpu::Buffer,
    bytes: u64,
    read: impl FnOnce(&[u8]) -> T,
) -> Result<T, RenderError> {
    let slice = staging.slice(..bytes.max(4));
    let (tx, rx) = mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    wait(gpu)?;
    rx.recv()
        .map_err(|_| RenderError::Backend("buffer mapping was dropped".into()))?
        .map_err(|e| RenderError::Backend(format!("reading GPU memory back: {e}")))?;
    let out = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| RenderError::Backend(format!("reading GPU memory back: {e}")))?;
        read(&view[..bytes as usize])
    };
    staging.unmap();
    Ok(out)
}

/// Reads a 64-bit counter kept as two 32-bit words.
fn word64(words: &[u32], i: usize) -> u64 {
    u64::from(words[i]) | (u64::from(words[i + 1]) << 32)
}

/// The buffers and pipeline of one frame (or one set of explicit rays), and the timestamp
/// queries of its batches of dispatches.
struct Batches<'a> {
    p: &'a Prepared,
    pipeline: &'a wgpu::ComputePipeline,
    params: &'a wgpu::Buffer,
    stride: u64,
    rays: &'a wgpu::Buffer,
    out: &'a wgpu::Buffer,
    counters: &'a wgpu::Buffer,
    timestamps: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
}

impl Batches<'_> {
    fn new<'a>(
        p: &'a Prepared,
        pipeline: &'a wgpu::ComputePipeline,
        params: &'a wgpu::Buffer,
        stride: u64,
        rays: &'a wgpu::Buffer,
        out: &'a wgpu::Buffer,
        counters: &'a wgpu::Buffer,
    ) -> Batches<'a> {
        let gpu = &p.gpu;
        let timestamps = gpu.timestamps.then(|| {
            let n = 2 * PASSES_PER_SUBMIT as u64;
            (
                gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: n as u32,
                }),
                buffer(
                    gpu,
                    "timestamps",
                    n * 8,
                    wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                ),
                buffer(
                    gpu,
                    "timestamps staging",
                    n * 8,
                    wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                ),
            )
        });
        Batches {
            p,
            pipeline,
            params,
            stride,
            rays,
            out,
            counters,
            timestamps,
        }
    }

    fn bind_group(&self) -> wgpu::BindGroup {
        let p = self.p;
        let entries = [
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: self.params,
                    offset: 0,
                    size: NonZeroU64::new(std::mem::size_of::<Params>() as u64),
                }),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: p.nodes.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: p.prims.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: p.prim_info.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: p.shading.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: self.rays.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 6,
                resource: self.out.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 7,
                resource: self.counters.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 8,
                resource: p.wide.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 9,
                resource: p.geo.as_entire_binding(),
            },
        ];
        p.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("raybench frame"),
            layout: &p.kernels.layout,
            entries: &entries,
        })
    }

    /// Runs dispatches `(params slot, workgroups)` in submissions of at most
    /// [`PASSES_PER_SUBMIT`] passes and returns the GPU execution seconds.
    fn run(&self, dispatches: &[(u64, u32)]) -> Result<f64, RenderError> {
        let gpu = &self.p.gpu;
        let bind_group = self.bind_group();
        let mut seconds = 0.0;
        for batch in dispatches.chunks(PASSES_PER_SUBMIT) {
            let mut encoder = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            for (i, &(slot, workgroups)) in batch.iter().enumerate() {
                let timestamp_writes =
                    self.timestamps
                        .as_ref()
                        .map(|(qs, _, _)| wgpu::ComputePassTimestampWrites {
                            query_set: qs,
                            beginning_of_pass_write_index: Some(2 * i as u32),
                            end_of_pass_write_index: Some(2 * i as u32 + 1),
                        });
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: None,
                    timestamp_writes,
                });
                pass.set_pipeline(self.pipeline);
                pass.set_bind_group(0, &bind_group, &[(slot * self.stride) as u32]);
                pass.dispatch_workgroups(workgroups, 1, 1);
            }
            let n = 2 * batch.len() as u32;
            if let Some((qs, resolve, staging)) = &self.timestamps {
                encoder.resolve_query_set(qs, 0..n, resolve, 0);
                encoder.copy_buffer_to_buffer(resolve, 0, staging, 0, u64::from(n) * 8);
            }
            let start = Instant::now();
            gpu.queue.submit([encoder.finish()]);
            wait(gpu)?;
            let wall = start.elapsed().as_secs_f64();
            device_errors(gpu, "running a kernel")?;
            seconds += match &self.timestamps {
                None => wall,
                Some((_, _, staging)) => read_back(gpu, staging, u64::from(n) * 8, |b| {
                    let ticks: &[u64] = bytemuck::cast_slice(b);
                    ticks
                        .chunks_exact(2)
                        .map(|w| w[1].saturating_sub(w[0]) as f64)
                        .sum::<f64>()
                        * gpu.timestamp_period
                        * 1e-9
                })?,
            };
        }
        Ok(seconds)
    }

    /// Copies the first `bytes` of `src` back to the host.
    fn fetch<T>(
        &self,
        src: &wgpu::Buffer,
        bytes: u64,
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, RenderError> {
        let gpu = &self.p.gpu;
        let staging = buffer(
            gpu,
            "staging",
            bytes,
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        );
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.copy_buffer_to_buffer(src, 0, &staging, 0, bytes.max(4));
        gpu.queue.submit([encoder.finish()]);
        read_back(gpu, &staging, bytes, read)
    }
}

impl Prepared {
    /// Uploads `params` into one aligned slot each; returns the buffer and the stride.
    fn upload_params(&self, params: &[Params]) -> (wgpu::Buffer, u64) {
        let align = u64::from(self.gpu.limits.min_uniform_buffer_offset_alignment).max(16);
        let stride = (std::mem::size_of::<Params>() as u64).div_ceil(align) * align;
        let mut bytes = vec![0u8; (stride * params.len() as u64) as usize];
        for (i, p) in params.iter().enumerate() {
            let at = i * stride as usize;
            bytes[at..at + std::mem::size_of::<Params>()].copy_from_slice(bytemuck::bytes_of(p));
        }
        let buf = buffer_init(&self.gpu, "params", &bytes, wgpu::BufferUsages::UNIFORM);
        (buf, stride)
    }

    fn counters_buffer(&self) -> wgpu::Buffer {
        buffer_init(
            &self.gpu,
            "counters",
            &[0u8; 24],
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )
    }

    /// Rays, tests and node visits from the counters buffer.
    fn read_counters(
        &self,
        f: &Batches<'_>,
        count: bool,
    ) -> Result<(u64, Option<RayCounters>), RenderError> {
        let words: Vec<u32> = f.fetch(f.counters, 24, |b| bytemuck::cast_slice(b).to_vec())?;
        let rays = word64(&words, 0);
        let counters = count.then(|| RayCounters {
            prim_tests: word64(&words, 2),
            node_visits: word64(&words, 4),
        });
        Ok((rays, counters))
    }
}

impl Renderer for WgpuRenderer {
    fn name(&self) -> &str {
        &self.name
    }

    fn description(&self) -> &str {
        &self.description
    }

    fn availability(&self) -> Result<(), String> {
        gpu(&self.request).map(|_| ())
    }

    /// Every mode has a kernel; once prepared, the volume modes are refused where the
    /// scene's volumes did not fit the device (`SceneData::volumes`).
    fn supports_mode(&self, mode: Mode) -> Result<(), String> {
        entry_point(Some(mode))?;
        if matches!(mode, Mode::Mip | Mode::Composite)
            && let Some(Err(why)) = self.prepared.as_ref().map(|p| &p.data.volumes)
        {
            return Err(why.clone());
        }
        Ok(())
    }

    fn supports(&self, scene: &Scene) -> Result<(), String> {
        check_kinds(scene)?;
        // Textures, shading normals (the instanced meshes' too) and the environment map
        // are ported (`shading`).
        // The largest buffer: the primitives (48 bytes each, plus the emitter list and each
        // instanced mesh's primitives once).
        if let Ok(g) = gpu(&self.request) {
            let meshes: usize = scene.geometry.meshes().iter().map(|m| m.len()).sum();
            let need = (scene.geometry.len() + scene.emitters.ids.len() + meshes) as u64 * 48;
            let limit = Self::binding_limit(&g);
            if need > limit {
                return Err(format!(
                    "the primitives need {need} bytes, more than the {limit} bytes a storage \
                     buffer may hold on {}",
                    g.info.name
                ));
            }
            // The shading data in `geo`: textures, the environment map, attributes.
            let need = crate::shading::bytes_needed(scene);
            if need > limit {
                return Err(format!(
                    "the textures, environment map and shading attributes need {need} bytes, \
                     more than the {limit} bytes a storage buffer may hold on {}",
                    g.info.name
                ));
            }
        }
        Ok(())
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<Timings, RenderError> {
        self.prepared = None;
        let gpu = self.gpu()?;
        self.supports(scene).map_err(RenderError::Unsupported)?;
        let kernels = kernels(&gpu)?;
        let mut timings = Timings::default();
        let start = Instant::now();
        let bvh = match self.layout {
            Layout::Bvh2 => Bvh::build(Arc::clone(&scene.geometry)),
            Layout::Cwbvh => Bvh::build_with(Arc::clone(&scene.geometry), cwbvh::bvh2_params()),
        };
        if bvh.depth() + 1 > STACK_SIZE as usize {
            return Err(RenderError::Unsupported(format!(
                "BVH depth {} exceeds the GPU traversal stack",
                bvh.depth()
            )));
        }
        let (tree, stats) = match self.layout {
            Layout::Bvh2 => {
                let stats = bvh.stats();
                (Tree::Bvh2(bvh), stats)
            }
            Layout::Cwbvh => {
                let wide = Cwbvh::collapse(&bvh).map_err(RenderError::Unsupported)?;
                let stats = AccelStats {
                    memory_bytes: 0,
                    counts: vec![
                        ("nodes", wide.nodes.len() as u64),
                        ("leaves", wide.leaves),
                        ("depth", u64::from(wide.depth)),
                    ],
                };
                (Tree::Cwbvh(wide), stats)
            }
        };
        timings.push("build", start.elapsed().as_secs_f64());
        let start = Instant::now();
        let mut data = match &tree {
            Tree::Bvh2(bvh) => SceneData::new(scene, bvh2_nodes(bvh), Vec::new(), bvh.prim_ids()),
            Tree::Cwbvh(w) => SceneData::new(scene, Vec::new(), w.nodes.clone(), &w.prim_ids),
        }
        .map_err(RenderError::Unsupported)?;
        let limit = Self::binding_limit(&gpu);
        if let Ok((first, _)) = data.volumes {
            // Volumes too large for a binding refuse the volume modes only (dropped before
            // the instances are appended: dropping truncates `geo` where they start).
            let other = u64::from(first) * 16;
            if let Err(why) = crate::volume::fit(scene, other, limit, &gpu.info.name) {
                data.drop_volumes(why);
            }
        }
        crate::instances::append(scene, self.layout, &mut data)
            .map_err(RenderError::Unsupported)?;
        let geo_bytes = data.geo.len() as u64 * 16;
        if geo_bytes > limit {
            return Err(RenderError::Unsupported(format!(
                "the primitives' data needs {geo_bytes} bytes, more than a storage buffer may \
                 hold on {}",
                gpu.info.name
            )));
        }
        let node_bytes = (data.nodes.len() * 32 + data.wide.len() * 80) as u64;
        if node_bytes > limit {
            return Err(RenderError::Unsupported(format!(
                "the BVH needs {node_bytes} bytes, more than a storage buffer may hold on {}",
                gpu.info.name
            )));
        }
        // The primitives' own data (`geo`), known once encoded.
        let geo_bytes = data.geo.len() as u64 * 16;
        if geo_bytes > limit {
            return Err(RenderError::Unsupported(format!(
                "the primitives' own data (height-field vertices and trees, ...) needs \
                 {geo_bytes} bytes, more than a storage buffer may hold on {}",
                gpu.info.name
            )));
        }
        let usage = wgpu::BufferUsages::STORAGE;
        let nodes = buffer_init(&gpu, "nodes", bytemuck::cast_slice(&data.nodes), usage);
        let wide = buffer_init(&gpu, "wide nodes", bytemuck::cast_slice(&data.wide), usage);
        let prims = buffer_init(&gpu, "prims", bytemuck::cast_slice(&data.prims), usage);
        let prim_info = buffer_init(
            &gpu,
            "prim_info",
            bytemuck::cast_slice(&data.prim_info),
            usage,
        );
        let shading = buffer_init(&gpu, "shading", bytemuck::cast_slice(&data.shading), usage);
        let geo = buffer_init(&gpu, "geo", bytemuck::cast_slice(&data.geo), usage);
        // Uploads are queued; wait so that the phase measures the transfer.
        gpu.queue.submit([]);
        wait(&gpu)?;
        device_errors(&gpu, "uploading the scene")?;
        timings.push("upload", start.elapsed().as_secs_f64());
        let mut counts = stats.counts;
        if data.instancing.count > 0 {
            // As `TwoLevel::stats` counts them: the flat tree's, then the top level's.
            let top_nodes = data.nodes.len() as u64 - u64::from(data.instancing.top_root);
            counts.extend([
                ("top nodes", top_nodes),
                ("instances", u64::from(data.instancing.count)),
                ("meshes", scene.geometry.meshes().len() as u64),
            ]);
        }
        let stats = AccelStats {
            memory_bytes: data.bytes() as usize,
            counts,
        };
        self.prepared = Some(Prepared {
            gpu,
            kernels,
            scene: Arc::clone(scene),
            data,
            stats,
            tree,
            nodes,
            wide,
            prims,
            prim_info,
            shading,
            geo,
            features: Features::of(scene),
            frame_lock: Mutex::new(()),
        });
        Ok(timings)
    }

    fn render(&self, settings: &RenderSettings) -> Result<Frame, RenderError> {
        settings.validate()?;
        let p = self.prepared.as_ref().ok_or(RenderError::NotPrepared)?;
        let _frame = p.frame_lock.lock().unwrap_or_else(|e| e.into_inner());
        let start = Instant::now();
        let gpu = &p.gpu;
        let entry = entry_point(Some(settings.mode)).map_err(RenderError::Unsupported)?;
        // The volumes that did not fit the device (`SceneData::volumes`).
        self.supports_mode(settings.mode)
            .map_err(RenderError::Unsupported)?;
        let pipeline = p
            .kernels
            .pipeline(gpu, entry, settings.count, self.layout, p.features)?;
        let (w, h) = (settings.width, settings.height);
        let out_size = std::mem::size_of::<GpuOut>() as u64;
        let band_pixels = (Self::binding_limit(gpu) / out_size).min(1 << 24);
        let bands = plan::frame(
            w,
            h,
            settings.spp,
            plan::budget(settings.mode),
            band_pixels,
            plan::max_samples(gpu.info.device_type),
            gpu.limits.max_compute_workgroups_per_dimension,
        );

        // Upload: one parameter slot per dispatch.
        let upload_start = Instant::now();
        let base = p.data.params(&p.scene, settings)?;
        let mut params = Vec::new();
        for b in &bands {
            for d in &b.dispatches {
                params.push(Params {
                    band_y0: b.y0,
                    y0: d.y0,
                    rows: d.rows,
                    s0: d.s0,
                    s1: d.s1,
                    ..base
                });
            }
        }
        let (params_buf, stride) = p.upload_params(&params);
        let band_rows = bands.iter().map(|b| b.rows).max().unwrap_or(0);
        let out_bytes = u64::from(band_rows) * u64::from(w) * out_size;
        let out = buffer(
            gpu,
            "out",
            out_bytes,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        );
        let rays = buffer(gpu, "no rays", 32, wgpu::BufferUsages::STORAGE);
        let counters = p.counters_buffer();
        let f = Batches::new(p, &pipeline, &params_buf, stride, &rays, &out, &counters);
        let mut upload = upload_start.elapsed().as_secs_f64();

        let n = w as usize * h as usize;
        let mut frame = Frame {
            width: w,
            height: h,
            color: vec![Vec3::ZERO; n],
            ids: vec![NO_HIT; n],
            t: vec![f32::INFINITY; n],
            stats: FrameStats::default(),
            timings: Timings::default(),
        };
        // Cast mode and the volume modes sum their jittered samples; the CPU divides after
        // summing (`cast_tile`), as here.
        let sums = matches!(settings.mode, Mode::Cast | Mode::Mip | Mode::Composite);
        let scale = if sums && settings.spp > 1 {
            1.0 / settings.spp as f32
        } else {
            1.0
        };
        let (mut gpu_seconds, mut readback) = (0.0, 0.0);
        let mut slot = 0u64;
        for b in &bands {
            let clear = Instant::now();
            let mut encoder = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            encoder.clear_buffer(&out, 0, None);
            gpu.queue.submit([encoder.finish()]);
            upload += clear.elapsed().as_secs_f64();
            let dispatches: Vec<(u64, u32)> = b
                .dispatches
                .iter()
                .map(|d| {
                    slot += 1;
                    (slot - 1, d.workgroups)
                })
                .collect();
            gpu_seconds += f.run(&dispatches)?;
            let read_start = Instant::now();
            let pixels = b.rows as usize * w as usize;
            let first = b.y0 as usize * w as usize;
            f.fetch(&out, pixels as u64 * out_size, |bytes| {
                let outs: &[GpuOut] = bytemuck::cast_slice(bytes);
                for (i, o) in outs.iter().enumerate() {
                    let c = Vec3::new(o.v[0], o.v[1], o.v[2]);
                    frame.color[first + i] = if scale == 1.0 { c } else { c * scale };
                    frame.t[first + i] = o.v[3];
                    frame.ids[first + i] = o.id;
                }
            })?;
            readback += read_start.elapsed().as_secs_f64();
        }
        let (rays_traced, counted) = p.read_counters(&f, settings.count)?;
        frame.stats = FrameStats {
            rays: rays_traced,
            counters: counted,
        };
        frame.timings.push("upload", upload);
        frame.timings.push("gpu", gpu_seconds);
        frame.timings.push("readback", readback);
        frame.timings.push("render", start.elapsed().as_secs_f64());
        Ok(frame)
    }

    fn structure(&self) -> Option<AccelStats> {
        self.prepared.as_ref().map(|p| p.stats.clone())
    }

    /// The figures of the tree the GPU walks (the CPU-built BVH2, or the CWBVH with the
    /// child boxes the kernel decodes), bytes per primitive counting the uploaded buffers.
    fn quality(&self, params: &QualityParams) -> Option<StructureQuality> {
        self.prepared.as_ref().map(|p| {
            let view = match &p.tree {
                Tree::Bvh2(bvh) => bvh.tree_view(),
                Tree::Cwbvh(w) => w.tree_view(),
            };
            StructureQuality::Tree(view.quality(&p.scene.geometry, params, p.stats.memory_bytes))
        })
    }

    fn trace_rays(
        &self,
        rays: &[Ray],
        count: bool,
    ) -> Result<(Vec<Option<Hit>>, Option<RayCounters>), RenderError> {
        self.trace_rays_phased(rays, count).map(|(h, c, _)| (h, c))
    }

    /// Any hit through the any-hit kernel ([`WgpuRenderer::occlude_rays_phased`]).
    fn occlude_rays(
        &self,
        rays: &[Ray],
        count: bool,
    ) -> Result<(Vec<bool>, Option<RayCounters>), RenderError> {
        self.occlude_rays_phased(rays, count)
            .map(|(b, c, _)| (b, c))
    }
}
