//! Compute pipelines with push descriptors, push constants and specialization constants.

use super::{context::Shared, Buffer, Context, Image};
use crate::error::{Error, Result, VkContext};
use crate::kernels;
use ash::vk;
use std::sync::Arc;

/// One resource bound by [`ComputePipeline::push_descriptors`], in binding order.
#[derive(Clone, Copy)]
pub enum Descriptor<'a> {
    /// A storage buffer.
    Buffer(&'a Buffer),
    /// A storage image in GENERAL layout.
    StorageImage(&'a Image),
    /// A view of a storage image in GENERAL layout that umbra does not own (a host engine's).
    StorageView(vk::ImageView),
    /// A read-only storage texel buffer (`readonly uimageBuffer`).
    Texels(&'a super::TexelBuffer),
}

impl Descriptor<'_> {
    fn ty(&self) -> vk::DescriptorType {
        match self {
            Descriptor::Buffer(_) => vk::DescriptorType::STORAGE_BUFFER,
            Descriptor::StorageImage(_) | Descriptor::StorageView(_) => vk::DescriptorType::STORAGE_IMAGE,
            Descriptor::Texels(_) => vk::DescriptorType::STORAGE_TEXEL_BUFFER,
        }
    }
}

/// What a kernel binds: descriptor types by binding number, push-constant size, constants.
/// Built from a kernel's interface by [`crate::gpu::kernel::Pipeline`].
#[derive(Debug, Clone, Default)]
pub struct PipelineDesc<'a> {
    /// `(binding number, type)` of each binding of set 0, in the order resources are pushed.
    pub bindings: &'a [(u32, vk::DescriptorType)],
    /// Bytes of push constants (0 for none); a multiple of 4.
    pub push_constant_size: u32,
    /// `(constant_id, value)` specialization constants (32-bit each).
    pub specialization: &'a [(u32, u32)],
}

/// A compute pipeline whose set 0 is a push-descriptor set.
pub struct ComputePipeline {
    shared: Arc<Shared>,
    /// The kernel's name.
    pub name: &'static str,
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    bindings: Vec<(u32, vk::DescriptorType)>,
    push_constant_size: u32,
}

impl ComputePipeline {
    /// Builds the pipeline for the embedded kernel `spirv/<kernel>.comp`.
    pub fn new(ctx: &Context, kernel: &str, desc: &PipelineDesc<'_>) -> Result<Self> {
        let k = kernels::kernel(kernel).ok_or_else(|| Error::MissingKernel(kernel.into()))?;
        let shared = &ctx.shared;
        let device = &shared.device;
        let layout_bindings: Vec<_> = desc
            .bindings
            .iter()
            .map(|&(binding, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let mut pipeline = Self {
            shared: shared.clone(),
            name: k.name,
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            bindings: desc.bindings.to_vec(),
            push_constant_size: desc.push_constant_size,
        };
        // SAFETY: valid device; every object is destroyed in Drop (null handles are ignored).
        unsafe {
            pipeline.set_layout = device
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default()
                        .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
                        .bindings(&layout_bindings),
                    None,
                )
                .call("vkCreateDescriptorSetLayout")?;
            let ranges = [vk::PushConstantRange::default()
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
                .size(desc.push_constant_size)];
            let set_layouts = [pipeline.set_layout];
            let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
            if desc.push_constant_size > 0 {
                layout_info = layout_info.push_constant_ranges(&ranges);
            }
            pipeline.layout =
                device.create_pipeline_layout(&layout_info, None).call("vkCreatePipelineLayout")?;

            let (words, folded) = if super::specialize::folding() {
                super::specialize::specialize(k.words(), desc.specialization)
            } else {
                (k.words().to_vec(), Default::default())
            };
            log::debug!(
                "kernel '{}': {} selections folded by its constants, {} blocks cut",
                k.name,
                folded.branches,
                folded.blocks_cut
            );
            let module = device
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)
                .call("vkCreateShaderModule")?;
            let entries: Vec<_> = desc
                .specialization
                .iter()
                .enumerate()
                .map(|(i, &(id, _))| vk::SpecializationMapEntry {
                    constant_id: id,
                    offset: 4 * i as u32,
                    size: 4,
                })
                .collect();
            let data: Vec<u8> = desc.specialization.iter().flat_map(|&(_, v)| v.to_ne_bytes()).collect();
            let spec = vk::SpecializationInfo::default().map_entries(&entries).data(&data);
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main")
                .specialization_info(&spec);
            let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(pipeline.layout)];
            let created = device.create_compute_pipelines(shared.pipeline_cache, &info, None);
            device.destroy_shader_module(module, None);
            pipeline.pipeline = created.map_err(|(_, e)| e).call("vkCreateComputePipelines")?[0];
        }
        Ok(pipeline)
    }

    /// Binds the pipeline.
    pub fn bind(&self, cmd: vk::CommandBuffer) {
        // SAFETY: a valid pipeline recorded into a command buffer in the recording state.
        unsafe { self.shared.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline) };
    }

    /// Pushes set 0: `resources` in the order of [`PipelineDesc::bindings`]. They must match the
    /// pipeline's bindings in number and type; a mismatch is an error, never a silently wrong
    /// binding.
    pub fn push_descriptors(&self, cmd: vk::CommandBuffer, resources: &[Descriptor<'_>]) -> Result<()> {
        let types: Vec<_> = resources.iter().map(Descriptor::ty).collect();
        if !types.iter().eq(self.bindings.iter().map(|(_, ty)| ty)) {
            return Err(Error::Invalid(format!(
                "kernel '{}' binds {:?} but was given {:?}",
                self.name, self.bindings, types
            )));
        }
        let buffers: Vec<[vk::DescriptorBufferInfo; 1]> = resources
            .iter()
            .map(|r| match r {
                Descriptor::Buffer(b) => [b.descriptor()],
                _ => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let images: Vec<[vk::DescriptorImageInfo; 1]> = resources
            .iter()
            .map(|r| match r {
                Descriptor::StorageImage(i) => [i.descriptor()],
                Descriptor::StorageView(view) => [vk::DescriptorImageInfo::default()
                    .image_view(*view)
                    .image_layout(vk::ImageLayout::GENERAL)],
                _ => [vk::DescriptorImageInfo::default()],
            })
            .collect();
        let views: Vec<[vk::BufferView; 1]> = resources
            .iter()
            .map(|r| match r {
                Descriptor::Texels(t) => [t.view],
                _ => [vk::BufferView::null()],
            })
            .collect();
        let writes: Vec<_> = resources
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let w =
                    vk::WriteDescriptorSet::default().dst_binding(self.bindings[i].0).descriptor_type(r.ty());
                match r {
                    Descriptor::Buffer(_) => w.buffer_info(&buffers[i]),
                    Descriptor::StorageImage(_) | Descriptor::StorageView(_) => w.image_info(&images[i]),
                    Descriptor::Texels(_) => w.texel_buffer_view(&views[i]),
                }
            })
            .collect();
        // SAFETY: writes match the set layout (checked above).
        unsafe {
            self.shared.push_descriptor.cmd_push_descriptor_set(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &writes,
            )
        };
        Ok(())
    }

    /// Pushes the kernel's push constants. `T` must be `Pod` and exactly the declared size.
    pub fn push_constants<T: bytemuck::Pod>(&self, cmd: vk::CommandBuffer, value: &T) -> Result<()> {
        let bytes = bytemuck::bytes_of(value);
        if bytes.len() as u32 != self.push_constant_size {
            return Err(Error::Invalid(format!(
                "kernel '{}' takes {} bytes of push constants, given {}",
                self.name,
                self.push_constant_size,
                bytes.len()
            )));
        }
        if bytes.is_empty() {
            return Ok(());
        }
        // SAFETY: size checked against the layout's range.
        unsafe {
            self.shared.device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, bytes)
        };
        Ok(())
    }

    /// Records one dispatch of the kernel: binds the pipeline, pushes `resources` and the push
    /// constants `push`, and dispatches enough `local`-sized workgroups to cover `size`
    /// invocations. The caller records the barrier that orders it with what follows.
    pub fn record<T: bytemuck::Pod>(
        &self,
        cmd: vk::CommandBuffer,
        resources: &[Descriptor<'_>],
        push: &T,
        size: [u32; 3],
        local: [u32; 3],
    ) -> Result<()> {
        self.bind(cmd);
        self.push_descriptors(cmd, resources)?;
        self.push_constants(cmd, push)?;
        self.dispatch(cmd, size, local)
    }

    /// Dispatches enough `local`-sized workgroups to cover `size` invocations. Sets the pass
    /// marker ([`Context::last_pass`]) and, in a command buffer of [`Context::submit`], records
    /// the GPU-written breadcrumb after the dispatch (an execution barrier and a 4-byte fill).
    pub fn dispatch(&self, cmd: vk::CommandBuffer, size: [u32; 3], local: [u32; 3]) -> Result<()> {
        let groups: [u32; 3] = std::array::from_fn(|i| size[i].div_ceil(local[i].max(1)));
        let max = self.shared.info.max_compute_work_group_count;
        if (0..3).any(|i| groups[i] > max[i]) {
            return Err(Error::Invalid(format!(
                "kernel '{}': {groups:?} workgroups exceed the device's {max:?}",
                self.name
            )));
        }
        self.shared.mark_pass(cmd, self.name);
        // SAFETY: recording into a command buffer in the recording state.
        unsafe { self.shared.device.cmd_dispatch(cmd, groups[0], groups[1], groups[2]) };
        self.shared.breadcrumb(cmd, self.name);
        Ok(())
    }
    /// Dispatches the workgroup counts a kernel wrote into `buffer` at `offset` (a
    /// `VkDispatchIndirectCommand`; `buffer` made with `INDIRECT_BUFFER` usage, the writes made
    /// visible by [`super::barrier::compute_to_indirect`]). Marks and breadcrumbs as
    /// [`ComputePipeline::dispatch`].
    pub fn dispatch_indirect(&self, cmd: vk::CommandBuffer, buffer: vk::Buffer, offset: u64) {
        self.shared.mark_pass(cmd, self.name);
        // SAFETY: recording into a command buffer in the recording state; the caller's buffer.
        unsafe { self.shared.device.cmd_dispatch_indirect(cmd, buffer, offset) };
        self.shared.breadcrumb(cmd, self.name);
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses the pipeline (umbra waits; hosts must too).
        unsafe {
            let d = &self.shared.device;
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
