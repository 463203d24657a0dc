//! Buffers through gpu-allocator, with an explicit staging path for upload and readback.

use super::{barrier, context::Shared, Context};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// A Vulkan buffer and its memory. Freed on drop.
pub struct Buffer {
    shared: Arc<Shared>,
    /// The raw handle.
    pub raw: vk::Buffer,
    /// Size in bytes.
    pub size: u64,
    allocation: Option<Allocation>,
    name: String,
}

impl Buffer {
    /// Creates a buffer of `size` bytes in `location`; at least 4, so an empty list still makes a
    /// valid binding (a kernel told it has no elements never reads it).
    pub fn new(
        ctx: &Context,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let shared = &ctx.shared;
        let limit = shared.info.max_storage_buffer_range;
        if usage.contains(vk::BufferUsageFlags::STORAGE_BUFFER) && size > limit {
            return Err(Error::Invalid(format!(
                "buffer '{name}' needs {size} bytes but device '{}' binds at most {limit} bytes \
                 per storage buffer",
                shared.info.name
            )));
        }
        let size = size.max(4);
        let (raw, allocation) = create_bound(shared, name, size, usage, location)?;
        Ok(Self { shared: shared.clone(), raw, size, allocation: Some(allocation), name: name.into() })
    }

    /// A device-local buffer filled with `data` through a staging buffer and a GPU copy (the path
    /// a discrete GPU needs; lavapipe would also accept a direct write).
    pub fn upload<T: bytemuck::Pod>(
        ctx: &Context,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
    ) -> Result<Self> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let size = bytes.len() as u64;
        let buffer =
            Self::new(ctx, name, size, usage | vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuOnly)?;
        if size == 0 {
            return Ok(buffer);
        }
        let mut staging = Self::new(
            ctx,
            &format!("{name} (staging)"),
            size,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        staging.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        ctx.submit(|cmd| {
            let region = [vk::BufferCopy::default().size(size)];
            // SAFETY: both buffers are at least `size` bytes.
            unsafe { ctx.device().cmd_copy_buffer(cmd, staging.raw, buffer.raw, &region) };
            barrier::transfer_to_compute(ctx, cmd);
            Ok(())
        })?;
        Ok(buffer)
    }

    /// Copies the buffer back to the host through a staging buffer. Waits for the GPU.
    pub fn read<T: bytemuck::Pod>(&self, ctx: &Context) -> Result<Vec<T>> {
        let mut readback = Self::new(
            ctx,
            &format!("{} (readback)", self.name),
            self.size,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        ctx.submit(|cmd| {
            barrier::compute_to_transfer(ctx, cmd);
            let region = [vk::BufferCopy::default().size(self.size)];
            // SAFETY: both buffers are `self.size` bytes.
            unsafe { ctx.device().cmd_copy_buffer(cmd, self.raw, readback.raw, &region) };
            barrier::transfer_to_host(ctx, cmd);
            Ok(())
        })?;
        readback.read_mapped()
    }

    /// The mapped bytes of a host-visible buffer.
    pub fn mapped_mut(&mut self) -> Result<&mut [u8]> {
        let name = self.name.clone();
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| Error::Invalid(format!("buffer '{name}' is not host-visible")))
    }

    /// Reads a host-visible buffer's contents as `T`s.
    pub fn read_mapped<T: bytemuck::Pod>(&mut self) -> Result<Vec<T>> {
        let size = self.size as usize;
        let bytes = &self.mapped_mut()?[..size];
        let count = size / std::mem::size_of::<T>();
        Ok(bytemuck::pod_collect_to_vec(&bytes[..count * std::mem::size_of::<T>()]))
    }

    /// The descriptor info for binding the whole buffer.
    pub fn descriptor(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo::default().buffer(self.raw).range(vk::WHOLE_SIZE)
    }
}

/// A buffer read as a storage texel buffer of one format (`readonly uimageBuffer` in GLSL, read
/// with `imageLoad`): the buffer and its view, destroyed together (the view first). The formats
/// umbra uses (R32_UINT, R32G32B32A32_UINT) support storage texel buffers on every device.
pub struct TexelBuffer {
    /// The view the kernels bind.
    pub view: vk::BufferView,
    /// The buffer.
    pub buffer: Buffer,
}

impl TexelBuffer {
    /// Uploads `data` (through [`Buffer::upload`]; readable back with [`Buffer::read`]) and
    /// views it as `format` texels of
    /// `texel_bytes` bytes each. An empty list uploads one zeroed element, never read: a view
    /// needs at least one texel. The texel count must be within the device's
    /// `maxTexelBufferElements`.
    pub fn upload<T: bytemuck::Pod>(
        ctx: &Context,
        name: &str,
        data: &[T],
        format: vk::Format,
        texel_bytes: u64,
    ) -> Result<Self> {
        let zeroed = [T::zeroed()];
        let data = if data.is_empty() { &zeroed[..] } else { data };
        let usage = vk::BufferUsageFlags::STORAGE_TEXEL_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let buffer = Buffer::upload(ctx, name, data, usage)?;
        Self::view(buffer, name, format, texel_bytes)
    }

    /// A device-local texel buffer of `texels` (at least one) `format` texels of `texel_bytes`
    /// bytes each, contents undefined until a kernel or a copy writes them; `usage` adds to the
    /// texel-buffer and transfer usages (`STORAGE_BUFFER`: a kernel may also bind
    /// [`TexelBuffer::buffer`] as a storage buffer).
    pub fn new(
        ctx: &Context,
        name: &str,
        texels: u64,
        format: vk::Format,
        texel_bytes: u64,
        usage: vk::BufferUsageFlags,
    ) -> Result<Self> {
        let usage = usage
            | vk::BufferUsageFlags::STORAGE_TEXEL_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let buffer = Buffer::new(ctx, name, texels.max(1) * texel_bytes, usage, MemoryLocation::GpuOnly)?;
        Self::view(buffer, name, format, texel_bytes)
    }

    /// Views `buffer` as `format` texels, checking the device's `maxTexelBufferElements`.
    fn view(buffer: Buffer, name: &str, format: vk::Format, texel_bytes: u64) -> Result<Self> {
        let shared = &buffer.shared;
        let texels = buffer.size / texel_bytes;
        let limit = shared.info.max_texel_buffer_elements as u64;
        if texels > limit {
            return Err(Error::Invalid(format!(
                "buffer '{name}' holds {texels} texels but device '{}' views at most {limit} per texel buffer",
                shared.info.name
            )));
        }
        let info = vk::BufferViewCreateInfo::default()
            .buffer(buffer.raw)
            .format(format)
            .offset(0)
            .range(texels * texel_bytes);
        // SAFETY: a valid buffer; the view is destroyed in Drop, before the buffer.
        let view = unsafe { shared.device.create_buffer_view(&info, None) }.call("vkCreateBufferView")?;
        Ok(Self { view, buffer })
    }
}

impl Drop for TexelBuffer {
    fn drop(&mut self) {
        // SAFETY: as for Buffer: no pending submission uses the view. The buffer field drops
        // after this, so the view goes first.
        unsafe { self.buffer.shared.device.destroy_buffer_view(self.view, None) };
    }
}

/// A buffer of `size` bytes with its memory from the allocator, bound: what [`Buffer::new`] wraps,
/// and the breadcrumb buffers that [`Shared`] pools (a `Buffer` holds the `Shared` it came from,
/// so those cannot be `Buffer`s). On an error nothing is left to free.
pub(super) fn create_bound(
    shared: &Shared,
    name: &str,
    size: u64,
    usage: vk::BufferUsageFlags,
    location: MemoryLocation,
) -> Result<(vk::Buffer, Allocation)> {
    let info =
        vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
    // SAFETY: valid device; the buffer is destroyed on error here, else by the caller.
    let raw = match unsafe { shared.device.create_buffer(&info, None) } {
        // A size no heap can hold: name the buffer, as an allocator failure would.
        Err(vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY) => {
            return Err(Error::Allocation {
                name: format!("{name} ({size} bytes)"),
                source: gpu_allocator::AllocationError::OutOfMemory,
            })
        }
        other => other.call("vkCreateBuffer")?,
    };
    let requirements = unsafe { shared.device.get_buffer_memory_requirements(raw) };
    let allocation = shared
        .allocate(name, requirements, location, true)
        .inspect_err(|_| unsafe { shared.device.destroy_buffer(raw, None) })?;
    // SAFETY: memory from the allocator for this buffer's requirements.
    let bound = unsafe { shared.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) };
    if let Err(e) = bound.call("vkBindBufferMemory") {
        unsafe { shared.device.destroy_buffer(raw, None) };
        let _ = shared.allocator().free(allocation);
        return Err(e);
    }
    Ok((raw, allocation))
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: umbra waits for its submissions; a host recording umbra's work keeps the
        // buffer alive until its own submission has finished.
        unsafe { self.shared.device.destroy_buffer(self.raw, None) };
        if let Some(allocation) = self.allocation.take() {
            let _ = self.shared.allocator().free(allocation);
        }
    }
}
