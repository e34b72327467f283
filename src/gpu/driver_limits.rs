//! What an adapter's driver cannot do that wgpu's `Limits` do not say, found from its
//! `AdapterInfo` in this one place and kept on the context ([`DriverLimits`] in
//! `GpuContext::driver_limits`). Each entry is a documented limit of one driver, matched
//! by the driver name Vulkan reports (`VkPhysicalDeviceDriverProperties::driverName`,
//! wgpu's `AdapterInfo::driver`); a driver that reports none is matched by the start of
//! its device name. Passes read the limits, never the adapter's name.

/// One driver's documented limits.
struct KnownDriver {
    /// The driver's name as Vulkan reports it.
    driver: &'static str,
    /// The most iterations one shader loop runs before the driver ends it.
    loop_iterations: u64,
}

/// Drivers known to end long loops early and silently: llvmpipe (Mesa's lavapipe) leaves
/// any loop after 65,535 iterations (gallivm's `LP_MAX_TGSI_LOOP_ITERATIONS`), so a light
/// loop past it drops every later light without an error.
const KNOWN: &[KnownDriver] = &[KnownDriver {
    driver: "llvmpipe",
    loop_iterations: 65_535,
}];

/// Limits of the adapter's driver beyond wgpu's `Limits`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DriverLimits {
    /// The most iterations one shader loop may run before the driver ends it early
    /// without an error; `None` where no such limit is known.
    pub loop_iterations: Option<u64>,
}

impl DriverLimits {
    /// The documented limits of `info`'s driver (none for a driver not listed).
    pub fn of(info: &wgpu::AdapterInfo) -> Self {
        let known = KNOWN.iter().find(|k| {
            info.driver == k.driver || (info.driver.is_empty() && info.name.starts_with(k.driver))
        });
        Self {
            loop_iterations: known.map(|k| k.loop_iterations),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(name: &str, driver: &str) -> wgpu::AdapterInfo {
        let mut info = wgpu::AdapterInfo::new(wgpu::DeviceType::Cpu, wgpu::Backend::Vulkan);
        info.name = name.into();
        info.driver = driver.into();
        info
    }

    #[test]
    fn llvmpipe_is_known_by_its_driver_and_others_have_no_loop_limit() {
        let llvmpipe = DriverLimits::of(&info("llvmpipe (LLVM 15.0.6, 256 bits)", "llvmpipe"));
        assert_eq!(llvmpipe.loop_iterations, Some(65_535));
        // No driver name reported: the device name's start.
        let unnamed = DriverLimits::of(&info("llvmpipe (LLVM 19.1.7, 256 bits)", ""));
        assert_eq!(unnamed.loop_iterations, Some(65_535));
        let nvidia = DriverLimits::of(&info("NVIDIA H100 80GB HBM3", "NVIDIA"));
        assert_eq!(nvidia.loop_iterations, None);
        // A name that merely mentions llvmpipe is not the driver.
        let other = DriverLimits::of(&info("not llvmpipe", "other"));
        assert_eq!(other.loop_iterations, None);
    }
}
