//! Storage images (declared formats, as lavapipe requires) and their readback.

use super::{barrier, barrier::access, context::Shared, Buffer, Context};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// A 2D single-mip image with a view. Freed on drop.
pub struct Image {
    shared: Arc<Shared>,
    /// The raw handle.
    pub raw: vk::Image,
    /// A view of the whole image.
    pub view: vk::ImageView,
    /// Its format.
    pub format: vk::Format,
    /// Width and height.
    pub extent: vk::Extent2D,
    allocation: Option<Allocation>,
    name: String,
}

/// Bytes per texel of the formats umbra reads back.
fn texel_size(format: vk::Format) -> Option<u64> {
    match format {
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => Some(16),
        vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_SFLOAT | vk::Format::R32G32_UINT => Some(8),
        vk::Format::R8G8B8A8_UNORM | vk::Format::R32_SFLOAT | vk::Format::R32_UINT => Some(4),
        _ => None,
    }
}

impl Image {
    /// A storage image of `width`×`height` in `format`, usable by kernels and copies.
    pub fn storage_2d(
        ctx: &Context,
        name: &str,
        width: u32,
        height: u32,
        format: vk::Format,
    ) -> Result<Self> {
        let shared = &ctx.shared;
        let max = shared.info.max_image_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(Error::Invalid(format!(
                "image '{name}' of {width}x{height}: each side must be between 1 and {max} on '{}'",
                shared.info.name
            )));
        }
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width, height, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(
                vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::TRANSFER_DST,
            )
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device; destroyed on error or in Drop.
        let raw = unsafe { shared.device.create_image(&info, None) }.call("vkCreateImage")?;
        let requirements = unsafe { shared.device.get_image_memory_requirements(raw) };
        let allocation = shared
            .allocate(name, requirements, MemoryLocation::GpuOnly, false)
            .inspect_err(|_| unsafe { shared.device.destroy_image(raw, None) })?;
        let mut image = Self {
            shared: shared.clone(),
            raw,
            view: vk::ImageView::null(),
            format,
            extent: vk::Extent2D { width, height },
            allocation: Some(allocation),
            name: name.into(),
        };
        // SAFETY: the memory is only bound, never freed here.
        let memory = image.allocation.as_ref().map(|a| (unsafe { a.memory() }, a.offset()));
        if let Some((memory, offset)) = memory {
            // SAFETY: memory allocated for this image's requirements.
            unsafe { shared.device.bind_image_memory(raw, memory, offset) }.call("vkBindImageMemory")?;
        }
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(barrier::color_range());
        // SAFETY: a bound image.
        image.view =
            unsafe { shared.device.create_image_view(&view_info, None) }.call("vkCreateImageView")?;
        Ok(image)
    }

    /// Moves the image from UNDEFINED to GENERAL for kernel access (contents discarded).
    pub fn init_general(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        barrier::image(
            ctx,
            cmd,
            self.raw,
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::GENERAL,
            access::NONE,
            access::COMPUTE_RW,
        );
    }

    /// Copies an image in GENERAL layout, last written by a kernel, back to the host as texels
    /// of `T` (e.g. `f32` for rgba32f: four per pixel, row-major). Waits for the GPU.
    pub fn read<T: bytemuck::Pod>(&self, ctx: &Context) -> Result<Vec<T>> {
        let texel = texel_size(self.format).ok_or_else(|| {
            Error::Invalid(format!("image '{}': readback of {:?} unsupported", self.name, self.format))
        })?;
        let size = texel * self.extent.width as u64 * self.extent.height as u64;
        let mut readback = Buffer::new(
            ctx,
            &format!("{} (readback)", self.name),
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        ctx.submit(|cmd| {
            self.record_copy_to(ctx, cmd, readback.raw);
            barrier::transfer_to_host(ctx, cmd);
            Ok(())
        })?;
        readback.read_mapped()
    }

    /// Fills the image (GENERAL layout afterwards) with texels of `T`, tightly packed, row-major,
    /// through a staging buffer. Waits for the GPU.
    pub fn write<T: bytemuck::Pod>(&self, ctx: &Context, texels: &[T]) -> Result<()> {
        let texel = texel_size(self.format).ok_or_else(|| {
            Error::Invalid(format!("image '{}': upload of {:?} unsupported", self.name, self.format))
        })?;
        let size = texel * self.extent.width as u64 * self.extent.height as u64;
        if std::mem::size_of_val(texels) as u64 != size {
            return Err(Error::Invalid(format!(
                "image '{}': {} bytes given for {size}",
                self.name,
                std::mem::size_of_val(texels)
            )));
        }
        let staging = Buffer::upload(
            ctx,
            &format!("{} (upload)", self.name),
            texels,
            vk::BufferUsageFlags::TRANSFER_SRC,
        )?;
        ctx.submit(|cmd| {
            barrier::image(
                ctx,
                cmd,
                self.raw,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                access::NONE,
                access::TRANSFER_WRITE,
            );
            // SAFETY: the staging buffer holds the whole image (checked above).
            unsafe {
                ctx.device().cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    self.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[self.copy_region()],
                )
            };
            barrier::image(
                ctx,
                cmd,
                self.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::ImageLayout::GENERAL,
                access::TRANSFER_WRITE,
                access::COMPUTE_RW,
            );
            Ok(())
        })
    }

    fn copy_region(&self) -> vk::BufferImageCopy {
        vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
            )
            .image_extent(vk::Extent3D { width: self.extent.width, height: self.extent.height, depth: 1 })
    }

    /// Records a copy of the image (GENERAL layout, written by kernels) into `buffer`, tightly
    /// packed, through TRANSFER_SRC_OPTIMAL and back to GENERAL.
    pub fn record_copy_to(&self, ctx: &Context, cmd: vk::CommandBuffer, buffer: vk::Buffer) {
        barrier::image(
            ctx,
            cmd,
            self.raw,
            vk::ImageLayout::GENERAL,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            access::COMPUTE_RW,
            access::TRANSFER_READ,
        );
        let region = [self.copy_region()];
        // SAFETY: the buffer holds the whole image (checked by the caller's size).
        unsafe {
            ctx.device().cmd_copy_image_to_buffer(
                cmd,
                self.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer,
                &region,
            )
        };
        barrier::image(
            ctx,
            cmd,
            self.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            vk::ImageLayout::GENERAL,
            access::TRANSFER_READ,
            access::COMPUTE_RW,
        );
    }

    /// The descriptor info for binding as a storage image in GENERAL layout.
    pub fn descriptor(&self) -> vk::DescriptorImageInfo {
        vk::DescriptorImageInfo::default().image_view(self.view).image_layout(vk::ImageLayout::GENERAL)
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: as for buffers, no submission using the image is pending.
        unsafe {
            self.shared.device.destroy_image_view(self.view, None);
            self.shared.device.destroy_image(self.raw, None);
        }
        if let Some(allocation) = self.allocation.take() {
            let _ = self.shared.allocator().free(allocation);
        }
    }
}
