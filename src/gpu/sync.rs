//! What every GPU path needs around its work: error scopes, the wait for the device, and
//! the size check against the device's buffer limits. Below both `kernel` and `rq`.

use std::time::Duration;

use super::GpuError;

/// How long one wait for the GPU may take before the render is abandoned as hung.
pub const GPU_TIMEOUT: Duration = Duration::from_secs(600);

/// Waits for the GPU, turning a hang or a lost device into an error.
pub(crate) fn wait(device: &wgpu::Device, during: &'static str) -> Result<(), GpuError> {
    match device.poll(wgpu::PollType::Wait {
        submission_index: None,
        timeout: Some(GPU_TIMEOUT),
    }) {
        Ok(_) => Ok(()),
        Err(wgpu::PollError::Timeout) => Err(GpuError::Timeout {
            during,
            seconds: GPU_TIMEOUT.as_secs(),
        }),
        Err(e) => Err(GpuError::Runtime {
            during,
            message: e.to_string(),
        }),
    }
}

/// Runs `f` inside error scopes for validation and out-of-memory errors.
#[cfg(not(target_arch = "wasm32"))]
pub(crate) fn scoped<T>(
    device: &wgpu::Device,
    during: &'static str,
    f: impl FnOnce() -> T,
) -> Result<T, GpuError> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let val = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = f();
    let v = pollster::block_on(val.pop());
    let o = pollster::block_on(oom.pop());
    match v.or(o) {
        None => Ok(out),
        Some(e) => Err(GpuError::Runtime {
            during,
            message: e.to_string(),
        }),
    }
}

/// In the browser a scope's error arrives only after control returns to the page's event
/// loop, so nothing can wait for it here: `f` runs as it is, and a WebGPU error reaches
/// the device's uncaptured-error handler (the page's console, and the embedder's
/// `on_uncaptured_error`) instead of this result.
#[cfg(target_arch = "wasm32")]
pub(crate) fn scoped<T>(
    _device: &wgpu::Device,
    _during: &'static str,
    f: impl FnOnce() -> T,
) -> Result<T, GpuError> {
    Ok(f())
}

pub(crate) fn check_size(
    device: &wgpu::Device,
    what: &'static str,
    needed: u64,
) -> Result<(), GpuError> {
    let l = device.limits();
    let limit = l.max_storage_buffer_binding_size.min(l.max_buffer_size);
    if needed > limit {
        return Err(GpuError::TooLarge {
            what,
            needed,
            limit,
        });
    }
    Ok(())
}
