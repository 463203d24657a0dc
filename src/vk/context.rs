//! The Vulkan context: umbra's own headless instance and device, or a host engine's handles.

use super::breadcrumb::{describe, CrumbBuffer, Trail};
use super::commands::DEFAULT_SUBMIT_TIMEOUT;
use super::debug::{messenger_info, ValidationLog};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc,
};
use gpu_allocator::MemoryLocation;
use gpu_allocator::{AllocationSizes, AllocatorDebugSettings};
use std::collections::HashMap;
use std::ffi::CStr;
use std::mem::ManuallyDrop;
use std::sync::atomic::AtomicU64;
use std::sync::{Arc, Mutex, MutexGuard};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create umbra's own context.
#[derive(Debug, Clone, Default)]
pub struct ContextDesc {
    /// Enable `VK_LAYER_KHRONOS_validation` with a messenger that collects every warning and error.
    /// `None` reads `UMBRA_VALIDATION=1` from the environment.
    pub validation: Option<bool>,
    /// Pick the first device whose name contains this (case-insensitive).
    /// `None` reads `UMBRA_DEVICE` from the environment.
    pub device: Option<String>,
}

/// A host engine's Vulkan objects, for building umbra on an existing device.
/// umbra never destroys any of them. The device must have been created with Vulkan 1.3,
/// `synchronization2` and `VK_KHR_push_descriptor` enabled.
pub struct HostDevice {
    /// The host's loader entry.
    pub entry: ash::Entry,
    /// The host's instance.
    pub instance: ash::Instance,
    /// The physical device behind `device`.
    pub physical_device: vk::PhysicalDevice,
    /// The host's logical device.
    pub device: ash::Device,
    /// A queue of `queue_family_index` that supports compute.
    pub queue: vk::Queue,
    /// The family of `queue`.
    pub queue_family_index: u32,
    /// The host's allocator; `None` makes umbra create one on the host's device.
    pub allocator: Option<Arc<Mutex<Allocator>>>,
    /// Whether the host enabled `shaderInt64` and `shaderBufferInt64Atomics` on `device`: the
    /// rasterized G-buffer's visibility buffer needs them (false: umbra ray-casts its G-buffers).
    pub int64_atomics: bool,
}

/// The push descriptors umbra's kernels may bind (each binds its resources by one push-descriptor
/// set): `maxPushDescriptors` on most GPUs. The kernels' interface is checked against it when
/// umbra is built (`src/gpu/interface.rs`, `MAX_KERNEL_BINDINGS`), and a device that offers fewer
/// is refused when the context is made, not when a kernel first binds past it.
pub const REQUIRED_PUSH_DESCRIPTORS: u32 = 32;

/// What umbra knows about the chosen device.
#[derive(Debug, Clone)]
pub struct DeviceInfo {
    /// Device name as the driver reports it.
    pub name: String,
    /// Discrete, integrated, CPU, ...
    pub device_type: vk::PhysicalDeviceType,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Valid bits of a timestamp on umbra's queue (0: no timestamps).
    pub timestamp_valid_bits: u32,
    /// Largest storage-buffer binding, in bytes.
    pub max_storage_buffer_range: u64,
    /// Largest number of texels one texel-buffer view addresses (`maxTexelBufferElements`).
    pub max_texel_buffer_elements: u32,
    /// Largest 2D image side.
    pub max_image_dimension_2d: u32,
    /// Largest workgroup count per dimension.
    pub max_compute_work_group_count: [u32; 3],
    /// Subgroup size (8 on lavapipe, 32 on NVIDIA): never assume one.
    pub subgroup_size: u32,
    /// The most descriptors one push-descriptor set holds (`maxPushDescriptors`: 32 on most
    /// GPUs and on lavapipe); at least [`REQUIRED_PUSH_DESCRIPTORS`] on a device umbra runs on.
    pub max_push_descriptors: u32,
    /// Vulkan API version of the device.
    pub api_version: u32,
    /// Whether the device offers 64-bit integer atomics on storage buffers
    /// (`shaderBufferInt64Atomics`, with `shaderInt64`, which SPIR-V's `Int64Atomics` implies) and on storage images (`VK_EXT_shader_image_atomic_int64`),
    /// as a visibility buffer's one-pass depth-and-id `atomicMin` uses them.
    pub int64_atomics: (bool, bool),
    /// Whether umbra's kernels may use them: `shaderInt64` and `shaderBufferInt64Atomics` are
    /// enabled on the device (umbra's own device enables them where offered; a host says so in
    /// [`HostDevice::int64_atomics`]). The rasterized G-buffer needs them; without, the G-buffer
    /// is ray-cast.
    pub int64_enabled: bool,
}

/// The shared core behind a [`Context`], kept alive by every resource made from it.
pub(crate) struct Shared {
    /// Kept alive: dropping the entry unloads libvulkan under the instance.
    #[allow(dead_code)]
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    #[allow(dead_code)]
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: Mutex<vk::Queue>,
    pub queue_family: u32,
    pub allocator: ManuallyDrop<Arc<Mutex<Allocator>>>,
    pub push_descriptor: ash::khr::push_descriptor::Device,
    pub pipeline_cache: vk::PipelineCache,
    pub info: DeviceInfo,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    validation: Option<Arc<ValidationLog>>,
    owned: bool,
    /// The pass marker: the last kernel dispatched into each command buffer still being
    /// recorded or submitted, so a failed submission names the pass (see [`Context::last_pass`]).
    pub passes: Mutex<HashMap<vk::CommandBuffer, &'static str>>,
    /// A failure the next [`Context::submit`] reports instead of submitting (tests only).
    #[cfg(feature = "testing")]
    pub injected_fault: Mutex<Option<vk::Result>>,
    /// A failure the next [`Context::submit`]'s wait reports after submitting (tests only).
    #[cfg(feature = "testing")]
    pub injected_wait_fault: Mutex<Option<vk::Result>>,
    /// The GPU-written breadcrumb of each command buffer [`Context::submit`] is recording or
    /// has submitted (see [`super::breadcrumb`]); a host's command buffers have none.
    pub trails: Mutex<HashMap<vk::CommandBuffer, Trail>>,
    /// Breadcrumb buffers no submission uses, for the next ones.
    pub crumbs: Mutex<Vec<CrumbBuffer>>,
    /// Command pools (reset, each with its one command buffer) no submission uses, for the next
    /// ones: a pool made and destroyed per submission costs driver work, and the validation
    /// layer's synchronization checks (1.3.239) keep state for every pool ever made.
    pub idle_pools: Mutex<Vec<(vk::CommandPool, vk::CommandBuffer)>>,
    /// Submissions a timeout gave up on while the GPU still ran them: freed once their fence
    /// signals ([`Context::wait_idle`], the next submit, or the context's drop).
    pub abandoned: Mutex<Vec<Abandoned>>,
    /// [`Context::submit`]'s timeout in nanoseconds.
    pub submit_timeout_ns: AtomicU64,
}

/// GPU memory held through a context's allocator ([`Context::memory_report`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryReport {
    /// Bytes in live allocations.
    pub allocated_bytes: u64,
    /// Bytes in the memory blocks that hold them (what the device has given).
    pub capacity_bytes: u64,
    /// Live allocations.
    pub allocations: usize,
}

/// What a timed-out submission holds until the GPU is done with it.
pub(crate) struct Abandoned {
    pub fence: vk::Fence,
    pub pool: vk::CommandPool,
    pub crumb: Option<CrumbBuffer>,
    /// The kernels it dispatched, to name where it still is.
    pub passes: Vec<&'static str>,
}

impl Shared {
    pub fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Memory for a resource with `requirements` (`linear`: a buffer or linear image), its
    /// failure named after `name`; the caller binds it and frees it with the resource.
    pub fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        location: MemoryLocation,
        linear: bool,
    ) -> Result<Allocation> {
        self.allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| Error::Allocation { name: name.into(), source })
    }

    /// Notes that `pass` is the latest kernel recorded into `cmd`.
    pub fn mark_pass(&self, cmd: vk::CommandBuffer, pass: &'static str) {
        self.passes.lock().unwrap_or_else(|p| p.into_inner()).insert(cmd, pass);
    }

    /// Writes the breadcrumb of the dispatch of `pass` just recorded into `cmd`, if `cmd` is one
    /// of [`Context::submit`]'s command buffers.
    pub fn breadcrumb(&self, cmd: vk::CommandBuffer, pass: &'static str) {
        if let Some(trail) = self.trails.lock().unwrap_or_else(|p| p.into_inner()).get_mut(&cmd) {
            trail.after_dispatch(&self.device, cmd, pass);
        }
    }

    /// Frees the abandoned submissions the GPU has finished, first waiting up to `wait`
    /// nanoseconds for all of them when given; returns how many are still running and, from the
    /// breadcrumb, where the first of them is.
    pub fn reclaim(&self, wait: Option<u64>) -> Result<(usize, Option<String>)> {
        let mut abandoned = self.abandoned.lock().unwrap_or_else(|p| p.into_inner());
        if abandoned.is_empty() {
            return Ok((0, None));
        }
        if let Some(timeout_ns) = wait {
            let fences: Vec<_> = abandoned.iter().map(|a| a.fence).collect();
            // SAFETY: valid fences of this device.
            match unsafe { self.device.wait_for_fences(&fences, true, timeout_ns) } {
                Ok(()) | Err(vk::Result::TIMEOUT) => {}
                Err(e) => return Err(e).call("vkWaitForFences"),
            }
        }
        let mut running = Vec::new();
        for a in abandoned.drain(..) {
            // SAFETY: a valid fence; once signalled, nothing of the submission is in use.
            if unsafe { self.device.get_fence_status(a.fence) } == Ok(true) {
                unsafe {
                    self.device.destroy_fence(a.fence, None);
                    self.device.destroy_command_pool(a.pool, None);
                }
                if let Some(crumb) = a.crumb {
                    self.crumbs.lock().unwrap_or_else(|p| p.into_inner()).push(crumb);
                }
            } else {
                running.push(a);
            }
        }
        let first = running.first().and_then(|a| describe(&a.passes, &a.crumb.as_ref()?.slots()));
        *abandoned = running;
        Ok((abandoned.len(), first))
    }
}

/// The instances and devices umbra creates for itself are created and destroyed one at a time
/// in a process. The API allows it concurrently, but drivers and the validation layers have
/// been seen to race there (reports against NVIDIA's driver and the layers from wgpu, blade and
/// ggml users; umbra's own parallel tests died twice of SIGSEGV at start-up in CI on lavapipe),
/// and a context is made rarely, so the lock costs nothing that matters.
static LIFETIME: Mutex<()> = Mutex::new(());

fn lifetime_lock() -> MutexGuard<'static, ()> {
    LIFETIME.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl Drop for Shared {
    fn drop(&mut self) {
        // SAFETY: every resource holds an Arc<Shared>, so none is alive any more; wait for the
        // queue, then destroy in reverse order of creation: cache, allocator, device, instance.
        unsafe {
            let _ = self.device.device_wait_idle();
            let abandoned = std::mem::take(self.abandoned.get_mut().unwrap_or_else(|p| p.into_inner()));
            let mut crumbs = std::mem::take(self.crumbs.get_mut().unwrap_or_else(|p| p.into_inner()));
            for a in abandoned {
                self.device.destroy_fence(a.fence, None);
                self.device.destroy_command_pool(a.pool, None);
                crumbs.extend(a.crumb);
            }
            for (pool, _) in std::mem::take(self.idle_pools.get_mut().unwrap_or_else(|p| p.into_inner())) {
                self.device.destroy_command_pool(pool, None);
            }
            for crumb in crumbs {
                crumb.destroy(self);
            }
            self.device.destroy_pipeline_cache(self.pipeline_cache, None);
            ManuallyDrop::drop(&mut self.allocator);
            if self.owned {
                let _one_at_a_time = lifetime_lock();
                self.device.destroy_device(None);
                if let Some((utils, messenger)) = self.debug.take() {
                    utils.destroy_debug_utils_messenger(messenger, None);
                }
                self.instance.destroy_instance(None);
            }
        }
    }
}

/// A Vulkan device ready for umbra's kernels. Cheap to clone.
#[derive(Clone)]
pub struct Context {
    pub(crate) shared: Arc<Shared>,
}

fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| !v.is_empty() && v != "0")
}

const NO_DRIVER: &str = "no Vulkan driver found. Install your GPU's Vulkan driver, or Mesa's \
software device lavapipe (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`). \
If VK_DRIVER_FILES or VK_ICD_FILENAMES is set, check that it names an existing driver manifest \
(lavapipe: /usr/share/vulkan/icd.d/lvp_icd.x86_64.json)";

impl Context {
    /// Creates umbra's own headless instance and device.
    pub fn new(desc: &ContextDesc) -> Result<Self> {
        let _one_at_a_time = lifetime_lock();
        let validation = desc.validation.unwrap_or_else(|| env_flag("UMBRA_VALIDATION"));
        let filter = desc.device.clone().or_else(|| std::env::var("UMBRA_DEVICE").ok());
        // SAFETY: loading the system's Vulkan loader library.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| {
            Error::NoDevice(format!(
                "the Vulkan loader (libvulkan.so.1) could not be loaded ({e}). Install it \
                 (Debian/Ubuntu: `apt-get install libvulkan1 mesa-vulkan-drivers`)"
            ))
        })?;

        let log = validation.then(|| Arc::new(ValidationLog::default()));
        let instance = create_instance(&entry, log.as_deref())?;
        let debug = match &log {
            Some(log) => {
                let utils = ash::ext::debug_utils::Instance::new(&entry, &instance);
                // SAFETY: valid instance; `log` outlives the messenger (both owned by Shared).
                let messenger = unsafe { utils.create_debug_utils_messenger(&messenger_info(log), None) };
                match messenger {
                    Ok(m) => Some((utils, m)),
                    Err(e) => {
                        unsafe { instance.destroy_instance(None) };
                        return Err(e).call("vkCreateDebugUtilsMessengerEXT");
                    }
                }
            }
            None => None,
        };
        let destroy_instance =
            |debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>| unsafe {
                if let Some((utils, m)) = debug {
                    utils.destroy_debug_utils_messenger(m, None);
                }
                instance.destroy_instance(None);
            };

        let (physical_device, queue_family) = match pick_device(&instance, filter.as_deref()) {
            Ok(p) => p,
            Err(e) => {
                destroy_instance(debug);
                return Err(e);
            }
        };
        let int64 = device_info(&instance, physical_device, queue_family).int64_atomics.0;
        let device = match create_device(&instance, physical_device, queue_family, int64) {
            Ok(d) => d,
            Err(e) => {
                destroy_instance(debug);
                return Err(e);
            }
        };
        // SAFETY: the family was created with one queue.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        Self::finish(
            entry,
            instance,
            physical_device,
            device,
            queue,
            queue_family,
            None,
            debug,
            log,
            true,
            int64,
        )
    }

    /// Builds umbra on a host engine's instance and device. Nothing of the host's is destroyed
    /// when the context is dropped; umbra's own objects (pipelines, its resources) are.
    pub fn from_host(host: HostDevice) -> Result<Self> {
        Self::finish(
            host.entry,
            host.instance,
            host.physical_device,
            host.device,
            host.queue,
            host.queue_family_index,
            host.allocator,
            None,
            None,
            false,
            host.int64_atomics,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn finish(
        entry: ash::Entry,
        instance: ash::Instance,
        physical_device: vk::PhysicalDevice,
        device: ash::Device,
        queue: vk::Queue,
        queue_family: u32,
        allocator: Option<Arc<Mutex<Allocator>>>,
        debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
        validation: Option<Arc<ValidationLog>>,
        owned: bool,
        int64_enabled: bool,
    ) -> Result<Self> {
        let mut info = device_info(&instance, physical_device, queue_family);
        info.int64_enabled = int64_enabled && info.int64_atomics.0;
        log::info!("umbra: using device '{}' ({:?})", info.name, info.device_type);
        let cleanup = |device: &ash::Device| unsafe {
            if owned {
                device.destroy_device(None);
                if let Some((utils, m)) = &debug {
                    utils.destroy_debug_utils_messenger(*m, None);
                }
                instance.destroy_instance(None);
            }
        };
        if let Err(missing) = check_push_descriptors(info.max_push_descriptors) {
            cleanup(&device);
            return Err(Error::Unsupported { device: info.name.clone(), missing });
        }
        let allocator = match allocator {
            Some(a) => a,
            None => {
                let created = Allocator::new(&AllocatorCreateDesc {
                    instance: instance.clone(),
                    device: device.clone(),
                    physical_device,
                    debug_settings: AllocatorDebugSettings::default(),
                    buffer_device_address: false,
                    allocation_sizes: AllocationSizes::new(32 << 20, 32 << 20),
                });
                match created {
                    Ok(a) => Arc::new(Mutex::new(a)),
                    Err(source) => {
                        cleanup(&device);
                        return Err(Error::Allocation { name: "allocator".into(), source });
                    }
                }
            }
        };
        // SAFETY: valid device; an empty cache.
        let pipeline_cache =
            match unsafe { device.create_pipeline_cache(&vk::PipelineCacheCreateInfo::default(), None) } {
                Ok(c) => c,
                Err(e) => {
                    drop(allocator);
                    cleanup(&device);
                    return Err(e).call("vkCreatePipelineCache");
                }
            };
        let push_descriptor = ash::khr::push_descriptor::Device::new(&instance, &device);
        Ok(Self {
            shared: Arc::new(Shared {
                entry,
                instance,
                physical_device,
                device,
                queue: Mutex::new(queue),
                queue_family,
                allocator: ManuallyDrop::new(allocator),
                push_descriptor,
                pipeline_cache,
                info,
                debug,
                validation,
                owned,
                passes: Mutex::new(HashMap::new()),
                #[cfg(feature = "testing")]
                injected_fault: Mutex::new(None),
                #[cfg(feature = "testing")]
                injected_wait_fault: Mutex::new(None),
                trails: Mutex::new(HashMap::new()),
                crumbs: Mutex::new(Vec::new()),
                idle_pools: Mutex::new(Vec::new()),
                abandoned: Mutex::new(Vec::new()),
                submit_timeout_ns: AtomicU64::new(DEFAULT_SUBMIT_TIMEOUT.as_nanos() as u64),
            }),
        })
    }

    /// The chosen device's properties.
    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }

    /// The pass marker of `cmd`: the kernel of the last pass recorded into it (each
    /// [`super::ComputePipeline::dispatch`] sets it). A host that records umbra's passes into its
    /// own command buffer can name the pass when its submission fails. umbra's own
    /// [`Context::submit`] names the pass the GPU was running instead (its breadcrumb), and this
    /// one only when the work never reached the GPU.
    pub fn last_pass(&self, cmd: vk::CommandBuffer) -> Option<&'static str> {
        self.shared.passes.lock().unwrap_or_else(|p| p.into_inner()).get(&cmd).copied()
    }

    /// Forgets `cmd`'s pass marker (for a host that frees or resets its command buffer).
    pub fn clear_pass(&self, cmd: vk::CommandBuffer) {
        self.shared.passes.lock().unwrap_or_else(|p| p.into_inner()).remove(&cmd);
    }

    /// Fault injection for tests of the reporting path: the next [`Context::submit`] records its
    /// work as usual but, instead of submitting it, fails with `result` as `vkQueueSubmit2` would
    /// (`ERROR_DEVICE_LOST`, `ERROR_OUT_OF_DEVICE_MEMORY`, ...). Nothing reaches the queue, so
    /// the context stays usable. Only with the `testing` feature, which umbra's tests turn on.
    #[cfg(feature = "testing")]
    #[doc(hidden)]
    pub fn inject_submit_fault(&self, result: vk::Result) {
        *self.shared.injected_fault.lock().unwrap_or_else(|p| p.into_inner()) = Some(result);
    }

    /// Fault injection for tests of the device-loss path: the next [`Context::submit`] submits
    /// its work for real and waits for it as usual (up to its timeout), then fails with `result`
    /// as `vkWaitForFences` would on a lost device, so the error names the pass the GPU had
    /// reached (its breadcrumb), not the last one recorded. Only with the `testing` feature.
    #[cfg(feature = "testing")]
    #[doc(hidden)]
    pub fn inject_wait_fault(&self, result: vk::Result) {
        *self.shared.injected_wait_fault.lock().unwrap_or_else(|p| p.into_inner()) = Some(result);
    }

    /// GPU memory held through the context's allocator (a host's own, when it shared one):
    /// bytes in live allocations, bytes in the memory blocks that hold them, and how many
    /// allocations there are. For leak checks and budgets.
    pub fn memory_report(&self) -> MemoryReport {
        let report = self.shared.allocator().generate_report();
        MemoryReport {
            allocated_bytes: report.total_allocated_bytes,
            capacity_bytes: report.total_capacity_bytes,
            allocations: report.allocations.len(),
        }
    }

    /// The logical device.
    pub fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    /// The validation messages collected so far, when validation is on. The log outlives the
    /// context, so messages from its destruction can be read after it is dropped.
    pub fn validation(&self) -> Option<Arc<ValidationLog>> {
        self.shared.validation.clone()
    }

    /// The pipeline cache's contents, for a host that wants to persist it.
    pub fn pipeline_cache_data(&self) -> Result<Vec<u8>> {
        // SAFETY: valid device and cache.
        unsafe { self.shared.device.get_pipeline_cache_data(self.shared.pipeline_cache) }
            .call("vkGetPipelineCacheData")
    }

    /// Lists every Vulkan device's name and type, for `umbra info`.
    pub fn list_devices() -> Result<Vec<(String, vk::PhysicalDeviceType)>> {
        let _one_at_a_time = lifetime_lock();
        // SAFETY: loading the system's Vulkan loader library.
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| Error::NoDevice(format!("the Vulkan loader could not be loaded: {e}")))?;
        let instance = create_instance(&entry, None)?;
        // SAFETY: valid instance, destroyed right after.
        let devices = unsafe {
            let list = instance.enumerate_physical_devices().unwrap_or_default();
            let named = list
                .iter()
                .map(|&pd| {
                    let p = instance.get_physical_device_properties(pd);
                    (device_name(&p), p.device_type)
                })
                .collect();
            instance.destroy_instance(None);
            named
        };
        Ok(devices)
    }
}

fn device_name(p: &vk::PhysicalDeviceProperties) -> String {
    p.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_else(|_| "<unnamed>".into())
}

fn create_instance(entry: &ash::Entry, log: Option<&ValidationLog>) -> Result<ash::Instance> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"umbra")
        .engine_name(c"umbra")
        .api_version(vk::API_VERSION_1_3);
    let mut layers = Vec::new();
    let mut extensions = Vec::new();
    let sync_validation = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync_validation);
    let mut messenger = log.map(messenger_info);
    if log.is_some() {
        // SAFETY: plain enumeration.
        let available = unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
        if !available.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)) {
            return Err(Error::NoDevice(
                "validation was requested but VK_LAYER_KHRONOS_validation is not installed \
                 (Debian/Ubuntu: `apt-get install vulkan-validationlayers`)"
                    .into(),
            ));
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        extensions.push(ash::ext::validation_features::NAME.as_ptr());
    }
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    if let Some(m) = messenger.as_mut() {
        info = info.push_next(m).push_next(&mut features);
    }
    // SAFETY: all pointers in `info` outlive the call.
    unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER | vk::Result::ERROR_INITIALIZATION_FAILED => {
            Error::NoDevice(format!("{NO_DRIVER} (vkCreateInstance: {e})"))
        }
        vk::Result::ERROR_LAYER_NOT_PRESENT | vk::Result::ERROR_EXTENSION_NOT_PRESENT => {
            Error::NoDevice(format!(
                "the Vulkan validation layer could not be enabled ({e}); install vulkan-validationlayers"
            ))
        }
        e => Error::Vulkan { call: "vkCreateInstance", result: e, pass: None },
    })
}

/// The compute queue family of a device that can run umbra, or why it cannot.
/// A device's `maxPushDescriptors` against [`REQUIRED_PUSH_DESCRIPTORS`].
fn check_push_descriptors(max: u32) -> Result<(), String> {
    if max < REQUIRED_PUSH_DESCRIPTORS {
        return Err(format!(
            "maxPushDescriptors is {max}, and umbra's kernels push up to {REQUIRED_PUSH_DESCRIPTORS} \
             descriptors"
        ));
    }
    Ok(())
}

fn check_device(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Result<u32, String> {
    // SAFETY: valid instance and physical device.
    unsafe {
        let props = instance.get_physical_device_properties(pd);
        if props.api_version < vk::API_VERSION_1_3 {
            return Err(format!(
                "Vulkan 1.3 required, device offers {}.{}",
                vk::api_version_major(props.api_version),
                vk::api_version_minor(props.api_version)
            ));
        }
        let family = instance
            .get_physical_device_queue_family_properties(pd)
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or("no compute queue")? as u32;
        let exts = instance.enumerate_device_extension_properties(pd).unwrap_or_default();
        if !exts.iter().any(|e| e.extension_name_as_c_str() == Ok(ash::khr::push_descriptor::NAME)) {
            return Err("VK_KHR_push_descriptor missing".into());
        }
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
        instance.get_physical_device_features2(pd, &mut f2);
        if f13.synchronization2 == vk::FALSE {
            return Err("synchronization2 missing".into());
        }
        let mut push = vk::PhysicalDevicePushDescriptorPropertiesKHR::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut push);
        instance.get_physical_device_properties2(pd, &mut props2);
        check_push_descriptors(push.max_push_descriptors)?;
        Ok(family)
    }
}

fn pick_device(instance: &ash::Instance, filter: Option<&str>) -> Result<(vk::PhysicalDevice, u32)> {
    // SAFETY: valid instance.
    let devices = unsafe { instance.enumerate_physical_devices() }.unwrap_or_default();
    if devices.is_empty() {
        return Err(Error::NoDevice(format!("{NO_DRIVER} (the loader reports no physical device)")));
    }
    let rank = |t: vk::PhysicalDeviceType| match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    };
    let mut candidates = Vec::new();
    let mut rejected = Vec::new();
    for pd in devices {
        // SAFETY: valid physical device.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = device_name(&props);
        if let Some(f) = filter {
            if !name.to_lowercase().contains(&f.to_lowercase()) {
                rejected.push(format!("{name} (does not match UMBRA_DEVICE={f})"));
                continue;
            }
        }
        match check_device(instance, pd) {
            Ok(family) => candidates.push((rank(props.device_type), pd, family)),
            Err(why) => rejected.push(format!("{name} ({why})")),
        }
    }
    candidates.sort_by_key(|c| c.0);
    candidates
        .first()
        .map(|&(_, pd, family)| (pd, family))
        .ok_or_else(|| Error::NoDevice(format!("no usable Vulkan device: {}", rejected.join("; "))))
}

/// Creates umbra's device, with 64-bit integers and their buffer atomics when `int64` (the
/// device offers both: `shaderBufferInt64Atomics` requires `shaderInt64`).
fn create_device(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    family: u32,
    int64: bool,
) -> Result<ash::Device> {
    let priorities = [1.0];
    let queues =
        [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    let extensions = [ash::khr::push_descriptor::NAME.as_ptr()];
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default().synchronization2(true);
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default().shader_buffer_int64_atomics(int64);
    let features = vk::PhysicalDeviceFeatures::default().shader_int64(int64);
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&extensions)
        .enabled_features(&features)
        .push_next(&mut f13)
        .push_next(&mut f12);
    // SAFETY: checked by `check_device`; pointers outlive the call.
    unsafe { instance.create_device(pd, &info, None) }.call("vkCreateDevice")
}

fn device_info(instance: &ash::Instance, pd: vk::PhysicalDevice, family: u32) -> DeviceInfo {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut push = vk::PhysicalDevicePushDescriptorPropertiesKHR::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup).push_next(&mut push);
    // SAFETY: valid physical device.
    let families = unsafe {
        instance.get_physical_device_properties2(pd, &mut props2);
        instance.get_physical_device_queue_family_properties(pd)
    };
    let p = props2.properties;
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut image64 = vk::PhysicalDeviceShaderImageAtomicInt64FeaturesEXT::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12).push_next(&mut image64);
    let int64;
    // SAFETY: valid physical device; an extension's structure the driver does not know stays
    // zeroed (false).
    let exts = unsafe {
        instance.get_physical_device_features2(pd, &mut f2);
        int64 = f2.features.shader_int64;
        instance.enumerate_device_extension_properties(pd).unwrap_or_default()
    };
    let image64_ext =
        exts.iter().any(|e| e.extension_name_as_c_str() == Ok(ash::ext::shader_image_atomic_int64::NAME));
    let int64_atomics = (
        f12.shader_buffer_int64_atomics == vk::TRUE && int64 == vk::TRUE,
        image64_ext && image64.shader_image_int64_atomics == vk::TRUE,
    );
    DeviceInfo {
        name: device_name(&p),
        device_type: p.device_type,
        timestamp_period: p.limits.timestamp_period,
        timestamp_valid_bits: families.get(family as usize).map_or(0, |f| f.timestamp_valid_bits),
        max_storage_buffer_range: p.limits.max_storage_buffer_range as u64,
        max_texel_buffer_elements: p.limits.max_texel_buffer_elements,
        max_image_dimension_2d: p.limits.max_image_dimension2_d,
        max_compute_work_group_count: p.limits.max_compute_work_group_count,
        subgroup_size: subgroup.subgroup_size,
        max_push_descriptors: push.max_push_descriptors,
        api_version: p.api_version,
        int64_atomics,
        int64_enabled: false,
    }
}

#[cfg(test)]
mod tests {
    /// A device with fewer push descriptors than umbra's kernels bind is refused, naming both.
    #[test]
    fn too_few_push_descriptors_are_refused() {
        assert_eq!(super::check_push_descriptors(32), Ok(()));
        assert_eq!(super::check_push_descriptors(64), Ok(()));
        assert_eq!(
            super::check_push_descriptors(31),
            Err("maxPushDescriptors is 31, and umbra's kernels push up to 32 descriptors".into())
        );
    }
}
