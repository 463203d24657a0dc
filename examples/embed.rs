//! A small host engine, written only with `ash` and `gpu-allocator`, that uses umbra on its own
//! device: it creates its instance, device, allocator, images and command buffer, writes a
//! G-buffer with its own kernel (`examples/embed_gbuffer.comp`), asks umbra to record SSAO,
//! deferred lighting and tone mapping into its command buffer (one frame graph, the host's pass
//! declared in it: every barrier between them is derived, SSAO's images allocated by umbra),
//! submits with its own fence and writes a PNG.
//!
//! ```sh
//! cargo run --example embed -- embed.png          # UMBRA_VALIDATION=1 turns the layer on
//! ```
//!
//! For comparison it also writes `<name>-umbra-gbuffer.png`: the same frame from umbra's own
//! ray-cast G-buffer (`Renderer::record_gbuffer`), recorded into the same command buffer.
//! `tests/embed.rs` runs [`run`] with validation on and compares the two.

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc,
};
use gpu_allocator::MemoryLocation;
use std::ffi::c_void;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use umbra::embed::Renderer;
use umbra::passes::ao::AoSettings;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::gbuffer::{GBufferImages, GBufferViews};
use umbra::passes::tonemap::ToneCurve;
use umbra::render::{HybridSettings, HybridTargets};
use umbra::scene::Scene;
use umbra::vk::{Context, Graph, HostDevice};

/// The host's G-buffer kernel, compiled by umbra's build script into `OUT_DIR`.
const GBUFFER_SPV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/embed_gbuffer.spv"));

/// What one run of the host produced.
pub struct Frames {
    /// Width and height.
    pub size: (u32, u32),
    /// RGBA8 sRGB pixels lit from the host's own G-buffer.
    pub host_gbuffer: Vec<u8>,
    /// RGBA8 sRGB pixels lit from umbra's ray-cast G-buffer.
    pub umbra_gbuffer: Vec<u8>,
    /// Validation messages the host's debug messenger received (0 when validation is off).
    pub validation_messages: usize,
    /// What the frame graph recorded: its passes, and its transient images and the physical
    /// images that held them.
    pub graph: umbra::vk::GraphStats,
}

/// The host's view of its world: one triangle per entry, material index in `a[3]`'s bits.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct HostTri {
    a: [f32; 4],
    b: [f32; 4],
    c: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct HostMaterial {
    base_metallic: [f32; 4],
    emission_roughness: [f32; 4],
    flags: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct HostCamera {
    origin: [f32; 4],
    forward: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    size: [u32; 4],
}

unsafe extern "system" fn count_messages(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: `user` is the host's counter, alive as long as the messenger; `data` is valid for
    // the duration of the call.
    unsafe {
        (*(user as *const AtomicUsize)).fetch_add(1, Ordering::SeqCst);
        let message = (*data).message_as_c_str().unwrap_or(c"?").to_string_lossy();
        eprintln!("validation {severity:?}: {message}");
    }
    vk::FALSE
}

/// A host image with its memory and view.
struct HostImage {
    image: vk::Image,
    view: vk::ImageView,
    allocation: Allocation,
}

/// A host buffer in host-visible memory.
struct HostBuffer {
    buffer: vk::Buffer,
    allocation: Allocation,
}

/// Everything the host owns, destroyed by the host in `destroy`.
struct Host {
    entry: ash::Entry,
    instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    messages: Box<AtomicUsize>,
    physical_device: vk::PhysicalDevice,
    device: ash::Device,
    queue_family: u32,
    queue: vk::Queue,
    allocator: Option<Arc<Mutex<Allocator>>>,
}

impl Host {
    fn new(validation: bool) -> Result<Self> {
        // SAFETY: loading the system's Vulkan loader.
        let entry = unsafe { ash::Entry::load() }.context("loading the Vulkan loader")?;
        let app = vk::ApplicationInfo::default()
            .application_name(c"umbra embed example")
            .api_version(vk::API_VERSION_1_3);
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let extensions = [ash::ext::debug_utils::NAME.as_ptr(), ash::ext::validation_features::NAME.as_ptr()];
        let messages = Box::new(AtomicUsize::new(0));
        let messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(count_messages))
            .user_data(&*messages as *const AtomicUsize as *mut c_void);
        // Synchronization validation too: it checks the barriers between the host's work and
        // umbra's.
        let checks = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&checks);
        let mut info = vk::InstanceCreateInfo::default().application_info(&app);
        if validation {
            info = info
                .enabled_layer_names(&layers)
                .enabled_extension_names(&extensions)
                .push_next(&mut features);
        }
        // SAFETY: the create info and everything it points to outlive the call.
        let instance = unsafe { entry.create_instance(&info, None) }.context(
            "vkCreateInstance (is a Vulkan 1.3 driver, and with validation the layer, installed?)",
        )?;
        let debug = if validation {
            let utils = ash::ext::debug_utils::Instance::new(&entry, &instance);
            // SAFETY: valid instance; the counter outlives the messenger (destroyed first).
            let messenger = unsafe { utils.create_debug_utils_messenger(&messenger_info, None) }?;
            Some((utils, messenger))
        } else {
            None
        };

        // The first device with Vulkan 1.3, a compute queue and push descriptors (umbra's needs).
        // SAFETY: valid instance.
        let candidates = unsafe { instance.enumerate_physical_devices() }?;
        let (physical_device, queue_family) = candidates
            .into_iter()
            .find_map(|pd| unsafe {
                let props = instance.get_physical_device_properties(pd);
                let push = instance
                    .enumerate_device_extension_properties(pd)
                    .unwrap_or_default()
                    .iter()
                    .any(|e| e.extension_name_as_c_str() == Ok(ash::khr::push_descriptor::NAME));
                let family = instance
                    .get_physical_device_queue_family_properties(pd)
                    .iter()
                    .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))?;
                (props.api_version >= vk::API_VERSION_1_3 && push).then_some((pd, family as u32))
            })
            .ok_or_else(|| anyhow!("no Vulkan 1.3 device with a compute queue and VK_KHR_push_descriptor"))?;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let device_extensions = [ash::khr::push_descriptor::NAME.as_ptr()];
        let mut features13 = vk::PhysicalDeviceVulkan13Features::default().synchronization2(true);
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&device_extensions)
            .push_next(&mut features13);
        // SAFETY: the physical device supports what is asked; pointers outlive the call.
        let device = unsafe { instance.create_device(physical_device, &device_info, None) }?;
        // SAFETY: the queue was requested above.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })?;
        Ok(Self {
            entry,
            instance,
            debug,
            messages,
            physical_device,
            device,
            queue_family,
            queue,
            allocator: Some(Arc::new(Mutex::new(allocator))),
        })
    }

    fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator.as_ref().expect("allocator alive").lock().expect("allocator lock")
    }

    fn image(&self, name: &str, (w, h): (u32, u32), format: vk::Format) -> Result<HostImage> {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: w, height: h, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device and create info; destroyed in `destroy_image`.
        unsafe {
            let image = self.device.create_image(&info, None)?;
            let requirements = self.device.get_image_memory_requirements(image);
            let allocation = self.allocator().allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })?;
            self.device.bind_image_memory(image, allocation.memory(), allocation.offset())?;
            let view = self.device.create_image_view(
                &vk::ImageViewCreateInfo::default()
                    .image(image)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(format)
                    .subresource_range(COLOR),
                None,
            )?;
            Ok(HostImage { image, view, allocation })
        }
    }

    fn buffer(
        &self,
        name: &str,
        bytes: usize,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<HostBuffer> {
        // SAFETY: valid device; destroyed in `destroy_buffer`.
        unsafe {
            let buffer = self.device.create_buffer(
                &vk::BufferCreateInfo::default().size(bytes.max(16) as u64).usage(usage),
                None,
            )?;
            let requirements = self.device.get_buffer_memory_requirements(buffer);
            let allocation = self.allocator().allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })?;
            self.device.bind_buffer_memory(buffer, allocation.memory(), allocation.offset())?;
            Ok(HostBuffer { buffer, allocation })
        }
    }

    fn upload<T: bytemuck::Pod>(&self, name: &str, data: &[T]) -> Result<HostBuffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut buffer =
            self.buffer(name, bytes.len(), vk::BufferUsageFlags::STORAGE_BUFFER, MemoryLocation::CpuToGpu)?;
        let mapped = buffer.allocation.mapped_slice_mut().ok_or_else(|| anyhow!("{name}: not mapped"))?;
        mapped[..bytes.len()].copy_from_slice(bytes);
        Ok(buffer)
    }

    fn destroy_image(&self, image: HostImage) -> Result<()> {
        // SAFETY: no pending work uses it (the host waited for its fence).
        unsafe {
            self.device.destroy_image_view(image.view, None);
            self.device.destroy_image(image.image, None);
        }
        self.allocator().free(image.allocation)?;
        Ok(())
    }

    fn destroy_buffer(&self, buffer: HostBuffer) -> Result<()> {
        // SAFETY: no pending work uses it.
        unsafe { self.device.destroy_buffer(buffer.buffer, None) };
        self.allocator().free(buffer.allocation)?;
        Ok(())
    }

    /// Destroys the allocator, device, messenger and instance (everything else is gone by now).
    fn destroy(mut self) -> usize {
        let allocator = self.allocator.take().expect("allocator alive");
        // umbra dropped its clones of the allocator with its Renderer and Context.
        drop(Arc::into_inner(allocator).expect("no one else holds the allocator"));
        // SAFETY: every object created on the device has been destroyed; the messenger goes
        // before its counter and the instance.
        unsafe {
            self.device.destroy_device(None);
            if let Some((utils, messenger)) = self.debug.take() {
                utils.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
        self.messages.load(Ordering::SeqCst)
    }
}

const COLOR: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

/// The host's world as its own GPU data, taken from a scene it also hands to umbra.
fn host_world(scene: &Scene) -> (Vec<HostTri>, Vec<HostMaterial>) {
    let p = |v: u32, w: f32| {
        let [x, y, z] = scene.positions[v as usize];
        [x, y, z, w]
    };
    let tris = scene
        .triangles
        .iter()
        .zip(&scene.triangle_material)
        .map(|(t, &m)| HostTri { a: p(t[0], f32::from_bits(m)), b: p(t[1], 0.0), c: p(t[2], 0.0) })
        .collect();
    let materials = scene
        .materials
        .iter()
        .map(|m| {
            let [r, g, b, _] = m.base_color_factor;
            let [er, eg, eb] = m.emissive;
            // umbra's G-buffer stores √α with α floored at 1e-4, as its BSDF floors it.
            let roughness = m.roughness.clamp(0.01, 1.0);
            HostMaterial {
                base_metallic: [r, g, b, m.metallic],
                emission_roughness: [er, eg, eb, roughness],
                flags: [m.double_sided as u32, 0, 0, 0],
            }
        })
        .collect();
    (tris, materials)
}

/// Renders the embedded Cornell box at `size` through the host's own G-buffer and through
/// umbra's, in one command buffer of the host's, and reads both frames back.
pub fn run(size: (u32, u32), validation: bool) -> Result<Frames> {
    let host = Host::new(validation)?;
    let scene = Scene::cornell_box();
    let camera = scene.camera(None)?;

    // umbra on the host's device, sharing its allocator.
    let ctx = Context::from_host(HostDevice {
        entry: host.entry.clone(),
        instance: host.instance.clone(),
        physical_device: host.physical_device,
        device: host.device.clone(),
        queue: host.queue,
        queue_family_index: host.queue_family,
        allocator: host.allocator.clone(),
        // The host's device enables no 64-bit atomics: umbra's G-buffers here are ray-cast.
        int64_atomics: false,
    })?;
    let clock = std::time::Instant::now();
    let renderer = Renderer::new(&ctx, &scene)?;
    println!("umbra's renderer made in {:.0} ms", clock.elapsed().as_secs_f64() * 1e3);

    // The host's resources: two G-buffers (its own, and one umbra fills), HDR and LDR targets.
    let gbuffer_formats = [
        ("depth", vk::Format::R32_SFLOAT),
        ("normal", vk::Format::R16G16B16A16_SFLOAT),
        ("base", vk::Format::R16G16B16A16_SFLOAT),
        ("emission", vk::Format::R16G16B16A16_SFLOAT),
        ("material", vk::Format::R32G32B32A32_UINT),
        ("layers", vk::Format::R32G32B32A32_UINT),
        ("layers2", vk::Format::R32G32B32A32_UINT),
        ("motion", vk::Format::R16G16B16A16_SFLOAT),
    ];
    let mut images = Vec::new();
    for set in ["host", "umbra"] {
        for (name, format) in gbuffer_formats {
            images.push(host.image(&format!("{set} gbuffer {name}"), size, format)?);
        }
        images.push(host.image(&format!("{set} hdr"), size, vk::Format::R32G32B32A32_SFLOAT)?);
        images.push(host.image(&format!("{set} ldr"), size, vk::Format::R8G8B8A8_UNORM)?);
    }
    const SET: usize = 10; // images per set: 8 G-buffer, hdr, ldr (SSAO's are umbra's, transient)
    let views = |set: usize| {
        let v = |i: usize| images[set * SET + i].view;
        GBufferViews {
            size,
            depth: v(0),
            normal: v(1),
            base: v(2),
            emission: v(3),
            material: v(4),
            layers: v(5),
            layers2: v(6),
            motion: v(7),
        }
    };
    let (host_views, umbra_views) = (views(0), views(1));
    let (tris, materials) = host_world(&scene);
    let tri_buffer = host.upload("host triangles", &tris)?;
    let material_buffer = host.upload("host materials", &materials)?;
    let pixels = (size.0 * size.1) as usize;
    let readback = [
        host.buffer(
            "readback host",
            pixels * 4,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?,
        host.buffer(
            "readback umbra",
            pixels * 4,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?,
    ];

    let device = &host.device;
    // SAFETY (this block): every handle is the host's and alive; the command buffer is recorded
    // and submitted once, and the host waits for its fence before reading or destroying anything.
    let (pool, layout, pipeline_layout, pipeline, descriptor_pool, fence) = unsafe {
        let pool = device.create_command_pool(
            &vk::CommandPoolCreateInfo::default().queue_family_index(host.queue_family),
            None,
        )?;
        // The host's own kernel with a classic descriptor set (not umbra's push descriptors).
        let bindings: Vec<_> = (0..7)
            .map(|i| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i)
                    .descriptor_type(if i < 2 {
                        vk::DescriptorType::STORAGE_BUFFER
                    } else {
                        vk::DescriptorType::STORAGE_IMAGE
                    })
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let layout = device.create_descriptor_set_layout(
            &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
            None,
        )?;
        let push = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(std::mem::size_of::<HostCamera>() as u32)];
        let layouts = [layout];
        let pipeline_layout = device.create_pipeline_layout(
            &vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts).push_constant_ranges(&push),
            None,
        )?;
        let code = ash::util::read_spv(&mut std::io::Cursor::new(GBUFFER_SPV))?;
        let module = device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        let pipeline = device
            .create_compute_pipelines(
                vk::PipelineCache::null(),
                &[vk::ComputePipelineCreateInfo::default().stage(stage).layout(pipeline_layout)],
                None,
            )
            .map_err(|(_, e)| e)?[0];
        device.destroy_shader_module(module, None);
        let sizes = [
            vk::DescriptorPoolSize { ty: vk::DescriptorType::STORAGE_BUFFER, descriptor_count: 2 },
            vk::DescriptorPoolSize { ty: vk::DescriptorType::STORAGE_IMAGE, descriptor_count: 5 },
        ];
        let descriptor_pool = device.create_descriptor_pool(
            &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
            None,
        )?;
        let fence = device.create_fence(&vk::FenceCreateInfo::default(), None)?;
        (pool, layout, pipeline_layout, pipeline, descriptor_pool, fence)
    };
    let recorded = unsafe {
        let set = device.allocate_descriptor_sets(
            &vk::DescriptorSetAllocateInfo::default().descriptor_pool(descriptor_pool).set_layouts(&[layout]),
        )?[0];
        let buffer_infos = [tri_buffer.buffer, material_buffer.buffer]
            .map(|b| [vk::DescriptorBufferInfo { buffer: b, offset: 0, range: vk::WHOLE_SIZE }]);
        let image_infos = host_views.in_order().map(|view| {
            [vk::DescriptorImageInfo::default().image_view(view).image_layout(vk::ImageLayout::GENERAL)]
        });
        let mut writes = Vec::new();
        for (i, info) in buffer_infos.iter().enumerate() {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info),
            );
        }
        // The host's scene has no layer textures: its shader writes the first five images, and
        // umbra never reads the last two (`layers`, `layers2`) for such a scene.
        for (i, info) in image_infos.iter().take(5).enumerate() {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(2 + i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                    .image_info(info),
            );
        }
        device.update_descriptor_sets(&writes, &[]);

        let cmd = device.allocate_command_buffers(
            &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
        )?[0];
        device.begin_command_buffer(
            cmd,
            &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
        )?;
        // The host moves its images to GENERAL (umbra's contract: storage images in GENERAL).
        let to_general: Vec<_> = images
            .iter()
            .map(|i| {
                vk::ImageMemoryBarrier2::default()
                    .src_stage_mask(vk::PipelineStageFlags2::NONE)
                    .dst_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                    .dst_access_mask(
                        vk::AccessFlags2::SHADER_STORAGE_WRITE | vk::AccessFlags2::SHADER_STORAGE_READ,
                    )
                    .old_layout(vk::ImageLayout::UNDEFINED)
                    .new_layout(vk::ImageLayout::GENERAL)
                    .image(i.image)
                    .subresource_range(COLOR)
            })
            .collect();
        device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&to_general));

        // One frame graph (`Renderer::record_graph`): the host's own G-buffer pass, its writes
        // declared, then umbra's passes on it. The graph derives every barrier between them from
        // what each pass reads and writes and allocates SSAO's images itself (transient); one
        // barrier ends the recording: the host places none of its own until its copies below.
        let settings = HybridSettings {
            size,
            lighting: LightingSettings { shadow_rays: 16, env: [0.3; 3], ..LightingSettings::default() },
            ao: Some(AoSettings { radius: 0.1, ..AoSettings::default() }),
            curve: ToneCurve::KhronosPbrNeutral,
            ..HybridSettings::default()
        };
        let target = |set: usize, gbuffer| HybridTargets {
            gbuffer,
            visibility: None,
            ao: None,
            hdr: images[set * SET + 8].view,
            ldr: Some(images[set * SET + 9].view),
            shadows: None,
            probes: None,
            lightmaps: None,
            reservoirs: None,
            taa: None,
        };
        let (host_targets, umbra_targets) = (target(0, &host_views), target(1, &umbra_views));
        // 1. The host's own G-buffer pass, which writes the seven images of `host_views`.
        let c = umbra::gpu::layout::GpuCamera::new(&camera, size);
        let v4 = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
        let push = HostCamera {
            origin: v4(c.origin),
            forward: v4(c.forward),
            right: v4(c.right),
            up: v4(c.up),
            size: [size.0, size.1, tris.len() as u32, c.orthographic() as u32],
        };
        let mut graph = Graph::new();
        let host_gbuffer = GBufferImages::import(&mut graph, &host_views);
        graph.add_pass("host gbuffer").write_all(host_gbuffer.images).record_raw(|cmd, _| {
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
            device.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                pipeline_layout,
                0,
                &[set],
                &[],
            );
            let push = bytemuck::bytes_of(&push);
            device.cmd_push_constants(cmd, pipeline_layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            device.cmd_dispatch(cmd, size.0.div_ceil(8), size.1.div_ceil(8), 1);
            Ok(())
        });
        // 2. umbra computes SSAO on the host's G-buffer, lights it (a dim constant sky as
        // image-based light, occluded by the SSAO) and tone-maps it into the host's images.
        let (passes, frame) = (renderer.passes(), renderer.frame(&camera));
        passes.add_hybrid_shading(&mut graph, frame, host_gbuffer, &host_targets, &settings)?;
        // 3. For comparison: umbra's own G-buffer, then the same passes.
        passes.add_hybrid(&mut graph, frame, &umbra_targets, &settings)?;
        let graph = renderer.record_graph(cmd, graph, None)?;

        // The host copies its LDR images out: its own barrier from umbra's compute writes, and
        // its own layout change (umbra leaves every image in GENERAL).
        let to_copy: Vec<_> = [&images[9], &images[SET + 9]]
            .iter()
            .map(|i| {
                vk::ImageMemoryBarrier2::default()
                    .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                    .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
                    .dst_stage_mask(vk::PipelineStageFlags2::COPY)
                    .dst_access_mask(vk::AccessFlags2::TRANSFER_READ)
                    .old_layout(vk::ImageLayout::GENERAL)
                    .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                    .image(i.image)
                    .subresource_range(COLOR)
            })
            .collect();
        device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&to_copy));
        for (image, buffer) in [&images[9], &images[SET + 9]].into_iter().zip(&readback) {
            let region = vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_extent(vk::Extent3D { width: size.0, height: size.1, depth: 1 });
            let layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
            device.cmd_copy_image_to_buffer(cmd, image.image, layout, buffer.buffer, &[region]);
        }
        let to_host = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&to_host));
        device.end_command_buffer(cmd)?;

        // The host submits with its own fence: umbra never submits this command buffer.
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        device.queue_submit2(host.queue, &[vk::SubmitInfo2::default().command_buffer_infos(&cmds)], fence)?;
        device.wait_for_fences(&[fence], true, u64::MAX)?;
        Ok::<_, anyhow::Error>(graph)
    };
    let graph = recorded?;
    let read = |b: &HostBuffer| -> Result<Vec<u8>> {
        Ok(b.allocation.mapped_slice().ok_or_else(|| anyhow!("readback not mapped"))?[..pixels * 4].to_vec())
    };
    let (host_gbuffer, umbra_gbuffer) = (read(&readback[0])?, read(&readback[1])?);

    // umbra goes first (it frees what it allocated, never the host's objects), then the host.
    drop(renderer);
    drop(ctx);
    // SAFETY: the fence was waited for; nothing is in flight.
    unsafe {
        device.destroy_fence(fence, None);
        device.destroy_descriptor_pool(descriptor_pool, None);
        device.destroy_pipeline(pipeline, None);
        device.destroy_pipeline_layout(pipeline_layout, None);
        device.destroy_descriptor_set_layout(layout, None);
        device.destroy_command_pool(pool, None);
    }
    for image in images {
        host.destroy_image(image)?;
    }
    for buffer in [tri_buffer, material_buffer].into_iter().chain(readback) {
        host.destroy_buffer(buffer)?;
    }
    let validation_messages = host.destroy();
    Ok(Frames { size, host_gbuffer, umbra_gbuffer, validation_messages, graph })
}

#[allow(dead_code)]
fn main() -> Result<()> {
    let output = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "embed.png".into()));
    let validation = std::env::var("UMBRA_VALIDATION").is_ok_and(|v| v == "1");
    let frames = run((256, 256), validation)?;
    let stem = output.with_extension("");
    let comparison = std::path::PathBuf::from(format!("{}-umbra-gbuffer.png", stem.display()));
    for (path, pixels) in [(&output, &frames.host_gbuffer), (&comparison, &frames.umbra_gbuffer)] {
        image::RgbaImage::from_raw(frames.size.0, frames.size.1, pixels.clone())
            .ok_or_else(|| anyhow!("pixel count"))?
            .save(path)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    if frames.validation_messages > 0 {
        bail!("{} validation message(s)", frames.validation_messages);
    }
    Ok(())
}
