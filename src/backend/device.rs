//! Instance and device creation, capability probing, the validation-message log.

use std::cell::Cell;
use std::ffi::{c_void, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, PoisonError, RwLock, RwLockReadGuard, RwLockWriteGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use raw_window_handle::{HasDisplayHandle, RawDisplayHandle};

use super::error::{BackendError, BackendResult, VkContext};
use super::resources::Arenas;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create a [`Gpu`].
#[derive(Clone, Debug, Default)]
pub struct GpuDesc {
    /// Enable `VK_LAYER_KHRONOS_validation` with synchronization validation; every message it
    /// reports is recorded in the [`ValidationLog`].
    pub validation: bool,
    /// Choose the physical device whose name contains this text (case-insensitive).
    pub device_name: Option<String>,
    /// Enable the instance extensions needed to present to a window on this display.
    pub display: Option<RawDisplayHandle>,
}

impl GpuDesc {
    /// Fills `display` from a window-system connection.
    pub fn with_display(mut self, display: &impl HasDisplayHandle) -> BackendResult<Self> {
        let handle = display
            .display_handle()
            .map_err(|e| BackendError::Unsupported(format!("window display handle: {e}")))?;
        self.display = Some(handle.as_raw());
        Ok(self)
    }
}

/// Messages from the validation layer, shared with the debug callback.
#[derive(Clone, Default)]
pub struct ValidationLog(Arc<Mutex<Vec<String>>>);

impl ValidationLog {
    /// Takes every message recorded so far.
    pub fn take(&self) -> Vec<String> {
        match self.0.lock() {
            Ok(mut v) => std::mem::take(&mut *v),
            Err(p) => std::mem::take(&mut *p.into_inner()),
        }
    }
    pub fn count(&self) -> usize {
        self.0.lock().map(|v| v.len()).unwrap_or(0)
    }
    fn push(&self, msg: String) {
        if let Ok(mut v) = self.0.lock() {
            v.push(msg);
        }
    }
}

/// What penumbra uses of the device, probed once.
#[derive(Clone, Debug)]
pub struct DeviceCaps {
    pub name: String,
    pub device_type: vk::PhysicalDeviceType,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: (u32, u32, u32),
    pub depth_clamp: bool,
    pub fill_mode_non_solid: bool,
    pub geometry_shader: bool,
    pub timestamp_compute_and_graphics: bool,
    pub timestamp_valid_bits: u32,
    pub timestamp_period_ns: f32,
    pub max_image_dimension_2d: u32,
    pub max_image_dimension_3d: u32,
    pub max_push_constants_size: u32,
    pub max_compute_work_group_invocations: u32,
    pub max_compute_work_group_size: [u32; 3],
    pub max_bound_descriptor_sets: u32,
    /// The most bytes one storage-buffer binding may cover (`maxStorageBufferRange`).
    pub max_storage_buffer_range: u32,
    /// The largest single memory allocation the driver promises (`maxMemoryAllocationSize`).
    pub max_memory_allocation_size: u64,
    pub depth_stencil_format: vk::Format,
    pub validation: bool,
    /// Uniform blocks are handed to the driver as read-only storage blocks (lavapipe; see
    /// `backend/uniform_blocks.rs`). `PENUMBRA_UNIFORM_BLOCKS_AS_STORAGE=0` or `=1` overrides.
    pub uniform_blocks_as_storage: bool,
}

impl DeviceCaps {
    /// Lines for `penumbra info`.
    pub fn report(&self) -> Vec<(String, String)> {
        let yes = |b: bool| if b { "yes" } else { "no" }.to_string();
        vec![
            ("device".into(), self.name.clone()),
            ("type".into(), format!("{:?}", self.device_type)),
            ("driver".into(), format!("{} ({})", self.driver_name, self.driver_info)),
            (
                "Vulkan".into(),
                format!("{}.{}.{}", self.api_version.0, self.api_version.1, self.api_version.2),
            ),
            ("dynamic rendering, synchronization2".into(), "yes (required)".into()),
            ("depth clamp".into(), yes(self.depth_clamp)),
            ("non-solid fill".into(), yes(self.fill_mode_non_solid)),
            ("geometry shader".into(), yes(self.geometry_shader)),
            (
                "timestamps".into(),
                if self.timestamp_valid_bits == 0 {
                    "unsupported on the graphics queue".into()
                } else {
                    format!(
                        "{} valid bits, period {} ns, compute+graphics {}",
                        self.timestamp_valid_bits,
                        self.timestamp_period_ns,
                        yes(self.timestamp_compute_and_graphics)
                    )
                },
            ),
            ("max 2D image".into(), self.max_image_dimension_2d.to_string()),
            (
                "max storage buffer".into(),
                format!(
                    "{} MiB a binding, {} MiB an allocation",
                    self.max_storage_buffer_range >> 20,
                    self.max_memory_allocation_size >> 20
                ),
            ),
            ("max 3D image".into(), self.max_image_dimension_3d.to_string()),
            (
                "max push constants".into(),
                format!("{} bytes", self.max_push_constants_size),
            ),
            (
                "max compute work group".into(),
                format!(
                    "{:?}, {} invocations",
                    self.max_compute_work_group_size, self.max_compute_work_group_invocations
                ),
            ),
            (
                "depth/stencil format".into(),
                format!("{:?}", self.depth_stencil_format),
            ),
            ("validation".into(), yes(self.validation)),
            (
                "uniform blocks bound as storage".into(),
                yes(self.uniform_blocks_as_storage),
            ),
        ]
    }
}

/// The device and everything allocated on it.
pub struct Gpu {
    pub(crate) entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    pub(crate) debug_instance: Option<ash::ext::debug_utils::Instance>,
    pub(crate) debug_device: Option<ash::ext::debug_utils::Device>,
    messenger: vk::DebugUtilsMessengerEXT,
    // Boxed so the callback's user-data pointer stays valid while the Gpu moves.
    _log_box: Box<ValidationLog>,
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) device: ash::Device,
    pub(crate) queue: vk::Queue,
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub(crate) command_pool: vk::CommandPool,
    pub(crate) caps: DeviceCaps,
    pub(crate) arenas: Arenas,
    pub(crate) frames: Vec<Option<std::cell::RefCell<super::frame::FrameData>>>,
    /// Open resource scopes, innermost last.
    pub(crate) scopes: Vec<super::resources::ResourceScope>,
    log: ValidationLog,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes a valid callback-data struct; `user` is the boxed ValidationLog that
    // outlives the messenger (destroyed first in Drop).
    let msg = unsafe {
        let data = &*data;
        let text = if data.p_message.is_null() {
            "(no message)".to_string()
        } else {
            CStr::from_ptr(data.p_message).to_string_lossy().into_owned()
        };
        format!("[{severity:?} {kind:?}] {text}")
    };
    // Info/verbose chatter from the loader is not a validation finding.
    if severity
        .intersects(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
    {
        crate::errln!("vulkan: {msg}");
        if !user.is_null() {
            let log = unsafe { &*(user as *const ValidationLog) };
            log.push(msg);
        }
    }
    vk::FALSE
}

fn cstr_field(bytes: &[std::ffi::c_char]) -> String {
    let bytes: Vec<u8> = bytes.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// The system Vulkan loader, loaded on first use and kept for the life of the process, with one
/// bare instance that is never destroyed. The loader unloads a driver when its last instance goes,
/// and loads it again for the next: `penumbra chart`, which creates a device per configuration,
/// then failed on NVIDIA's 580 driver with "Unable to find a Vulkan driver" after some dozens of
/// configurations (an H200; the same chart ran to the end with the driver preloaded), where
/// lavapipe reloads without complaint. The instance keeps the driver loaded; it costs a few
/// kilobytes and is created only once.
struct Loader {
    entry: ash::Entry,
    _keep_driver_loaded: Option<ash::Instance>,
}

fn vulkan_loader() -> BackendResult<ash::Entry> {
    static LOADER: std::sync::OnceLock<Result<Loader, String>> = std::sync::OnceLock::new();
    let loader = LOADER.get_or_init(|| {
        // SAFETY: loading the system Vulkan loader; failure is reported, not assumed. The static
        // holds the library, so every Entry cloned from it stays valid.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| e.to_string())?;
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_0);
        // SAFETY: a plain instance with no layers or extensions. Where none can be created,
        // Gpu::new's own attempt reports why.
        let keep = {
            let _change = device_set_change();
            unsafe { entry.create_instance(&vk::InstanceCreateInfo::default().application_info(&app), None) }.ok()
        };
        Ok(Loader {
            entry,
            _keep_driver_loaded: keep,
        })
    });
    loader
        .as_ref()
        .map(|l| l.entry.clone())
        .map_err(|e| BackendError::Loader(e.clone()))
}

// Vulkan calls on one thread against devices made or dropped on another. The Vulkan loader adds
// and frees entries of its process-wide device list without the lock its readers take
// (KhronosGroup/Vulkan-Loader#2018 upstream, still so in 1.4.341), and the validation layer of Debian 12
// (1.3.239) looks every call's device or instance up in a process-wide map that creating and
// destroying them change, with no lock at all. So a call on one thread could read an entry that
// another thread was adding or freeing: `cargo test`, which runs a binary's GPU tests on threads
// of their own, crashed now and then at address 0 or inside the layer's lookup
// (`tests/backend_threads.rs` crashed in 8 of 8 runs without this lock, in none of 12 with it).
// Making or dropping a device and its instance therefore holds this lock exclusively, and every
// other stretch of Vulkan calls holds it shared. A thread counts the holds it has, so nested
// stretches take the lock once and a device made or dropped inside one (nothing in penumbra does)
// goes ahead rather than deadlock.
static DEVICE_SET: RwLock<()> = RwLock::new(());

thread_local! {
    static HOLDS: Cell<u32> = const { Cell::new(0) };
}

/// The lock, held shared or exclusive by the outermost hold of a thread; dropping the hold
/// releases it (nested holds are taken and dropped innermost first, as scopes are).
pub(crate) struct DeviceSetLock {
    _shared: Option<RwLockReadGuard<'static, ()>>,
    _exclusive: Option<RwLockWriteGuard<'static, ()>>,
}

impl Drop for DeviceSetLock {
    fn drop(&mut self) {
        HOLDS.with(|h| h.set(h.get().saturating_sub(1)));
    }
}

fn hold(exclusive: bool) -> DeviceSetLock {
    let outermost = HOLDS.with(|h| {
        let n = h.get();
        h.set(n + 1);
        n == 0
    });
    // A poisoned lock still orders the calls: what it guards is the driver's state, not ours.
    DeviceSetLock {
        _shared: (outermost && !exclusive).then(|| DEVICE_SET.read().unwrap_or_else(PoisonError::into_inner)),
        _exclusive: (outermost && exclusive).then(|| DEVICE_SET.write().unwrap_or_else(PoisonError::into_inner)),
    }
}

/// Held around Vulkan calls on an existing device or instance.
pub(crate) fn vulkan_calls() -> DeviceSetLock {
    hold(false)
}

/// Held while a device or instance is made or dropped.
pub(crate) fn device_set_change() -> DeviceSetLock {
    hold(true)
}

impl Gpu {
    // long: one set-up recipe, instance to last object, under one exclusive hold and one tear-down path.
    pub fn new(desc: &GpuDesc) -> BackendResult<Gpu> {
        let entry = vulkan_loader()?;
        // From the instance to the last object of the new device, made under one exclusive hold.
        let _change = device_set_change();

        let layers = unsafe { entry.enumerate_instance_layer_properties() }.vk("vkEnumerateInstanceLayerProperties")?;
        let has_validation = layers
            .iter()
            .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER));
        if desc.validation && !has_validation {
            return Err(BackendError::Unsupported("validation requested but VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)".into()));
        }
        let available_exts = unsafe { entry.enumerate_instance_extension_properties(None) }
            .vk("vkEnumerateInstanceExtensionProperties")?;
        let has_ext = |name: &CStr| {
            available_exts
                .iter()
                .any(|e| e.extension_name_as_c_str().ok() == Some(name))
        };
        let debug_utils = has_ext(ash::ext::debug_utils::NAME);

        let mut ext_names: Vec<*const std::ffi::c_char> = Vec::new();
        if debug_utils {
            ext_names.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        if let Some(display) = desc.display {
            let needed = ash_window::enumerate_required_extensions(display)
                .map_err(|e| BackendError::Unsupported(format!("presenting to this window system: {e}")))?;
            for &n in needed {
                let name = unsafe { CStr::from_ptr(n) };
                if !has_ext(name) {
                    return Err(BackendError::Unsupported(format!(
                        "instance extension {} (needed to open a window)",
                        name.to_string_lossy()
                    )));
                }
                ext_names.push(n);
            }
        }
        let layer_names: Vec<*const std::ffi::c_char> = if desc.validation {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };

        let app_name = c"penumbra";
        let app_info = vk::ApplicationInfo::default()
            .application_name(app_name)
            .engine_name(app_name)
            .api_version(vk::API_VERSION_1_3);

        let log = ValidationLog::default();
        let log_box = Box::new(log.clone());
        let severity = vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR;
        let kinds = vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
            | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
            | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE;
        let user_ptr = &*log_box as *const ValidationLog as *mut c_void;
        let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(severity)
            .message_type(kinds)
            .pfn_user_callback(Some(debug_callback))
            .user_data(user_ptr);
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);

        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&ext_names);
        if desc.validation {
            create_info = create_info.push_next(&mut features);
            if debug_utils {
                // Also catches messages from vkCreateInstance/vkDestroyInstance themselves.
                create_info = create_info.push_next(&mut messenger_info);
            }
        }
        let instance = unsafe { entry.create_instance(&create_info, None) }.vk("vkCreateInstance")?;

        let (debug_instance, messenger) = if debug_utils {
            let di = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let m = if desc.validation {
                let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                    .message_severity(severity)
                    .message_type(kinds)
                    .pfn_user_callback(Some(debug_callback))
                    .user_data(user_ptr);
                unsafe { di.create_debug_utils_messenger(&info, None) }.vk("vkCreateDebugUtilsMessengerEXT")?
            } else {
                vk::DebugUtilsMessengerEXT::null()
            };
            (Some(di), m)
        } else {
            (None, vk::DebugUtilsMessengerEXT::null())
        };

        // From here on, a failure must tear down what was made.
        let result = Self::create_device(&entry, &instance, desc, debug_instance.as_ref());
        let (physical, device, queue_family, caps) = match result {
            Ok(v) => v,
            Err(e) => {
                unsafe {
                    if let Some(di) = &debug_instance {
                        if messenger != vk::DebugUtilsMessengerEXT::null() {
                            di.destroy_debug_utils_messenger(messenger, None);
                        }
                    }
                    instance.destroy_instance(None);
                }
                return Err(e);
            }
        };
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let debug_device = debug_instance
            .as_ref()
            .map(|_| ash::ext::debug_utils::Device::new(&instance, &device));

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            // Blocks start at 8 MiB and double as more are needed, up to gpu-allocator's defaults
            // (256 MiB device, 64 MiB host). Starting at the defaults cost a short bake on an
            // H200 about 13 ms of its 53 (the first 64 MiB of host-visible memory), and the
            // default scene's capture about 70 ms.
            allocation_sizes: gpu_allocator::AllocationSizes::new(8 << 20, 8 << 20)
                .with_max_device_memblock_size(256 << 20)
                .with_max_host_memblock_size(64 << 20),
        })
        .map_err(|e| BackendError::Allocation {
            name: "allocator".into(),
            message: e.to_string(),
        })?;

        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let command_pool = unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;

        let mut caps = caps;
        caps.validation = desc.validation;
        Ok(Gpu {
            entry,
            instance,
            debug_instance,
            debug_device,
            messenger,
            _log_box: log_box,
            physical,
            device,
            queue,
            queue_family,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            command_pool,
            caps,
            arenas: Arenas::default(),
            frames: Vec::new(),
            scopes: Vec::new(),
            log,
        })
    }

    // long: one recipe: pick the device, query its features and limits, enable what is used.
    fn create_device(
        _entry: &ash::Entry,
        instance: &ash::Instance,
        desc: &GpuDesc,
        _debug: Option<&ash::ext::debug_utils::Instance>,
    ) -> BackendResult<(vk::PhysicalDevice, ash::Device, u32, DeviceCaps)> {
        let physicals = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
        if physicals.is_empty() {
            return Err(BackendError::NoDevice(
                " found (is mesa-vulkan-drivers installed?)".into(),
            ));
        }
        let named: Vec<(vk::PhysicalDevice, vk::PhysicalDeviceProperties, String)> = physicals
            .iter()
            .map(|&p| {
                let props = unsafe { instance.get_physical_device_properties(p) };
                let name = cstr_field(&props.device_name);
                (p, props, name)
            })
            .collect();
        let rank = |t: vk::PhysicalDeviceType| match t {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 3,
            _ => 4,
        };
        let chosen = match &desc.device_name {
            Some(want) => {
                let want_l = want.to_lowercase();
                named
                    .iter()
                    .find(|(_, _, n)| n.to_lowercase().contains(&want_l))
                    .ok_or_else(|| {
                        let names: Vec<&str> = named.iter().map(|(_, _, n)| n.as_str()).collect();
                        BackendError::NoDevice(format!(" matches --device {want:?}; available: {}", names.join(", ")))
                    })?
            }
            None => named
                .iter()
                .filter(|(_, props, _)| props.api_version >= vk::API_VERSION_1_3)
                .min_by_key(|(_, props, _)| rank(props.device_type))
                .or_else(|| named.first())
                .ok_or_else(|| BackendError::NoDevice(" found".into()))?,
        };
        let (physical, props, name) = (chosen.0, chosen.1, chosen.2.clone());
        if props.api_version < vk::API_VERSION_1_3 {
            return Err(BackendError::Unsupported(format!(
                "{name} supports Vulkan {}.{}; penumbra needs 1.3 (dynamic rendering, synchronization2)",
                vk::api_version_major(props.api_version),
                vk::api_version_minor(props.api_version)
            )));
        }

        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut f13)
            .push_next(&mut f12);
        unsafe { instance.get_physical_device_features2(physical, &mut f2) };
        let base = f2.features;
        if f13.dynamic_rendering == 0 || f13.synchronization2 == 0 {
            return Err(BackendError::Unsupported(format!(
                "{name} lacks dynamicRendering or synchronization2"
            )));
        }

        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut v11 = vk::PhysicalDeviceVulkan11Properties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut driver)
            .push_next(&mut v11);
        unsafe { instance.get_physical_device_properties2(physical, &mut props2) };
        let driver_name = driver
            .driver_name_as_c_str()
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_default();
        let driver_info = driver
            .driver_info_as_c_str()
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_default();

        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let queue_family = families
            .iter()
            .position(|f| {
                f.queue_flags
                    .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
            })
            .ok_or_else(|| BackendError::Unsupported(format!("{name} has no graphics+compute queue")))?
            as u32;
        let timestamp_valid_bits = families[queue_family as usize].timestamp_valid_bits;

        let depth_stencil_format = [vk::Format::D32_SFLOAT_S8_UINT, vk::Format::D24_UNORM_S8_UINT]
            .into_iter()
            .find(|&f| {
                let p = unsafe { instance.get_physical_device_format_properties(physical, f) };
                p.optimal_tiling_features
                    .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
            })
            .ok_or_else(|| BackendError::Unsupported(format!("{name} has no depth+stencil attachment format")))?;

        let limits = props.limits;
        let caps = DeviceCaps {
            name: name.clone(),
            device_type: props.device_type,
            driver_name,
            driver_info,
            api_version: (
                vk::api_version_major(props.api_version),
                vk::api_version_minor(props.api_version),
                vk::api_version_patch(props.api_version),
            ),
            depth_clamp: base.depth_clamp != 0,
            fill_mode_non_solid: base.fill_mode_non_solid != 0,
            geometry_shader: base.geometry_shader != 0,
            timestamp_compute_and_graphics: limits.timestamp_compute_and_graphics != 0,
            timestamp_valid_bits,
            timestamp_period_ns: limits.timestamp_period,
            max_image_dimension_2d: limits.max_image_dimension2_d,
            max_image_dimension_3d: limits.max_image_dimension3_d,
            max_push_constants_size: limits.max_push_constants_size,
            max_compute_work_group_invocations: limits.max_compute_work_group_invocations,
            max_compute_work_group_size: limits.max_compute_work_group_size,
            max_bound_descriptor_sets: limits.max_bound_descriptor_sets,
            max_storage_buffer_range: limits.max_storage_buffer_range,
            max_memory_allocation_size: v11.max_memory_allocation_size,
            depth_stencil_format,
            validation: false,
            uniform_blocks_as_storage: match std::env::var("PENUMBRA_UNIFORM_BLOCKS_AS_STORAGE").as_deref() {
                Ok("0") => false,
                Ok("1") => true,
                _ => driver.driver_id == vk::DriverId::MESA_LLVMPIPE,
            },
        };

        // Enable only what is both used and present; methods check `caps` and fail with
        // `Unsupported` when they need a missing feature.
        let enabled = vk::PhysicalDeviceFeatures::default()
            .depth_clamp(caps.depth_clamp)
            .fill_mode_non_solid(caps.fill_mode_non_solid)
            .geometry_shader(caps.geometry_shader)
            .shader_storage_image_write_without_format(base.shader_storage_image_write_without_format != 0)
            .independent_blend(base.independent_blend != 0);
        let mut e13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true);
        let mut e12 = vk::PhysicalDeviceVulkan12Features::default()
            .host_query_reset(f12.host_query_reset != 0)
            .scalar_block_layout(f12.scalar_block_layout != 0);
        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let mut dev_exts: Vec<*const std::ffi::c_char> = Vec::new();
        if desc.display.is_some() {
            dev_exts.push(ash::khr::swapchain::NAME.as_ptr());
        }
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_features(&enabled)
            .enabled_extension_names(&dev_exts)
            .push_next(&mut e13)
            .push_next(&mut e12);
        let device = unsafe { instance.create_device(physical, &device_info, None) }.vk("vkCreateDevice")?;
        Ok((physical, device, queue_family, caps))
    }

    pub fn caps(&self) -> &DeviceCaps {
        &self.caps
    }

    /// The validation messages recorded so far (empty without validation).
    pub fn validation_log(&self) -> &ValidationLog {
        &self.log
    }

    pub fn wait_idle(&self) -> BackendResult<()> {
        let _calls = vulkan_calls();
        unsafe { self.device.device_wait_idle() }.vk("vkDeviceWaitIdle")
    }

    /// Gives a Vulkan object a debug-utils name (seen in validation messages and RenderDoc).
    pub(crate) fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(dd) = &self.debug_device {
            if let Ok(c) = CString::new(name) {
                let info = vk::DebugUtilsObjectNameInfoEXT::default()
                    .object_handle(handle)
                    .object_name(&c);
                // Naming is a debugging aid; a failure here must not fail the render.
                let _calls = vulkan_calls();
                let _ = unsafe { dd.set_debug_utils_object_name(&info) };
            }
        }
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // Everything the device owns goes with it, under the same exclusive hold.
        let _change = device_set_change();
        unsafe {
            let _ = self.device.device_wait_idle();
            for f in self.frames.drain(..).flatten() {
                f.into_inner().destroy(&self.device, &self.allocator);
            }
            self.arenas.destroy_all(&self.device, &self.allocator);
            self.device.destroy_command_pool(self.command_pool, None);
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some(di) = &self.debug_instance {
                if self.messenger != vk::DebugUtilsMessengerEXT::null() {
                    di.destroy_debug_utils_messenger(self.messenger, None);
                }
            }
            self.instance.destroy_instance(None);
        }
    }
}
