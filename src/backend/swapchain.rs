//! Window surface and swapchain for the demo.
//!
//! Present semaphores are per swapchain image (a semaphore signalled for image i may only be
//! reused once image i is acquired again); acquire semaphores are per frame slot and reused only
//! after that slot's fence has been waited for.

use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

use super::device::vulkan_calls;
use super::error::{BackendError, BackendResult, VkContext};
use super::resources::{ImageDesc, ImageId};
use super::Gpu;

pub struct Swapchain {
    surface_fn: ash::khr::surface::Instance,
    swapchain_fn: ash::khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    raw: vk::SwapchainKHR,
    pub images: Vec<ImageId>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    acquire_semaphores: Vec<vk::Semaphore>,
    present_semaphores: Vec<vk::Semaphore>,
}

#[derive(Clone, Copy, Debug)]
pub struct AcquiredImage {
    pub index: u32,
    pub image: ImageId,
    /// Wait on this before writing the image.
    pub acquired: vk::Semaphore,
    /// Signal this when done; presentation waits on it.
    pub rendered: vk::Semaphore,
}

impl Gpu {
    /// A swapchain for the window, with `slots` acquire semaphores (one per frame in flight).
    pub fn create_swapchain<W: HasDisplayHandle + HasWindowHandle>(
        &mut self,
        window: &W,
        size: (u32, u32),
        slots: usize,
    ) -> BackendResult<Swapchain> {
        let _calls = vulkan_calls();
        let display = window
            .display_handle()
            .map_err(|e| BackendError::Unsupported(format!("display handle: {e}")))?;
        let win = window
            .window_handle()
            .map_err(|e| BackendError::Unsupported(format!("window handle: {e}")))?;
        let surface =
            unsafe { ash_window::create_surface(&self.entry, &self.instance, display.as_raw(), win.as_raw(), None) }
                .vk("vkCreateSurfaceKHR")?;
        let surface_fn = ash::khr::surface::Instance::new(&self.entry, &self.instance);
        let supported =
            unsafe { surface_fn.get_physical_device_surface_support(self.physical, self.queue_family, surface) }
                .vk("vkGetPhysicalDeviceSurfaceSupportKHR")?;
        if !supported {
            unsafe { surface_fn.destroy_surface(surface, None) };
            return Err(BackendError::Unsupported(format!(
                "{} cannot present to this window",
                self.caps.name
            )));
        }
        let swapchain_fn = ash::khr::swapchain::Device::new(&self.instance, &self.device);
        let mut acquire_semaphores = Vec::new();
        for _ in 0..slots.max(1) {
            acquire_semaphores.push(
                unsafe { self.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                    .vk("vkCreateSemaphore")?,
            );
        }
        let mut sc = Swapchain {
            surface_fn,
            swapchain_fn,
            surface,
            raw: vk::SwapchainKHR::null(),
            images: Vec::new(),
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D::default(),
            acquire_semaphores,
            present_semaphores: Vec::new(),
        };
        self.recreate_swapchain(&mut sc, size)?;
        Ok(sc)
    }

    /// Rebuilds the swapchain at a new size (after a resize or an out-of-date present).
    pub fn recreate_swapchain(&mut self, sc: &mut Swapchain, size: (u32, u32)) -> BackendResult<()> {
        let _calls = vulkan_calls();
        self.wait_idle()?;
        let caps = unsafe {
            sc.surface_fn
                .get_physical_device_surface_capabilities(self.physical, sc.surface)
        }
        .vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        let formats = unsafe {
            sc.surface_fn
                .get_physical_device_surface_formats(self.physical, sc.surface)
        }
        .vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let format = formats
            .iter()
            .find(|f| f.format == vk::Format::B8G8R8A8_SRGB || f.format == vk::Format::R8G8B8A8_SRGB)
            .or(formats.first())
            .copied()
            .ok_or_else(|| BackendError::Unsupported("the surface offers no formats".into()))?;
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size.0.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size.1.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let wanted = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST;
        let usage = wanted & caps.supported_usage_flags;
        if !usage.contains(vk::ImageUsageFlags::COLOR_ATTACHMENT) {
            return Err(BackendError::Unsupported(
                "swapchain images as colour attachments".into(),
            ));
        }
        let old = sc.raw;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(sc.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(old);
        let raw = unsafe { sc.swapchain_fn.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        self.release_swapchain_images(sc);
        if old != vk::SwapchainKHR::null() {
            unsafe { sc.swapchain_fn.destroy_swapchain(old, None) };
        }
        sc.raw = raw;
        sc.format = format.format;
        sc.extent = extent;
        let raws = unsafe { sc.swapchain_fn.get_swapchain_images(raw) }.vk("vkGetSwapchainImagesKHR")?;
        for (i, r) in raws.into_iter().enumerate() {
            let desc =
                ImageDesc::new_2d(&format!("swapchain {i}"), format.format, extent.width, extent.height).usage(usage);
            sc.images.push(self.register_external_image(r, desc));
            sc.present_semaphores.push(
                unsafe { self.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                    .vk("vkCreateSemaphore")?,
            );
        }
        Ok(())
    }

    fn release_swapchain_images(&mut self, sc: &mut Swapchain) {
        let _calls = vulkan_calls();
        for id in sc.images.drain(..) {
            self.destroy_image(id);
        }
        for s in sc.present_semaphores.drain(..) {
            unsafe { self.device.destroy_semaphore(s, None) };
        }
    }

    /// Acquires the next image for frame slot `slot`. `Ok(None)`: the swapchain is out of date.
    pub fn acquire(&self, sc: &Swapchain, slot: usize) -> BackendResult<Option<AcquiredImage>> {
        let _calls = vulkan_calls();
        let acquired = sc.acquire_semaphores[slot % sc.acquire_semaphores.len()];
        match unsafe {
            sc.swapchain_fn
                .acquire_next_image(sc.raw, u64::MAX, acquired, vk::Fence::null())
        } {
            Ok((index, _suboptimal)) => Ok(Some(AcquiredImage {
                index,
                image: sc.images[index as usize],
                acquired,
                rendered: sc.present_semaphores[index as usize],
            })),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(None),
            Err(e) => Err(BackendError::Vulkan {
                call: "vkAcquireNextImageKHR",
                result: e,
            }),
        }
    }

    /// Presents; returns false when the swapchain must be recreated.
    pub fn present(&self, sc: &Swapchain, image: &AcquiredImage) -> BackendResult<bool> {
        let _calls = vulkan_calls();
        let waits = [image.rendered];
        let chains = [sc.raw];
        let indices = [image.index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&chains)
            .image_indices(&indices);
        match unsafe { sc.swapchain_fn.queue_present(self.queue, &info) } {
            Ok(false) => Ok(true),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(e) => Err(BackendError::Vulkan {
                call: "vkQueuePresentKHR",
                result: e,
            }),
        }
    }

    pub fn destroy_swapchain(&mut self, mut sc: Swapchain) {
        let _calls = vulkan_calls();
        let _ = self.wait_idle();
        self.release_swapchain_images(&mut sc);
        unsafe {
            for s in sc.acquire_semaphores.drain(..) {
                self.device.destroy_semaphore(s, None);
            }
            sc.swapchain_fn.destroy_swapchain(sc.raw, None);
            sc.surface_fn.destroy_surface(sc.surface, None);
        }
    }
}
