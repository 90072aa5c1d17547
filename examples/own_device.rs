//! Render on a wgpu device of your own (your adapter, your limits), then check the GPU's
//! image against the CPU mirror's: `cargo run --release --example own_device`.

use glint::{Backend, RenderOptions, Renderer, scene::Scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    }))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("my device"),
        required_limits: adapter.limits(),
        ..Default::default()
    }))?;

    let scene = Scene::load("scenes/mitsubishi.toml")?;
    let options = RenderOptions {
        size: Some((320, 240)),
        ..Default::default()
    };
    let gpu = Renderer::with_device(adapter.get_info(), device, queue)?;
    let on_gpu = gpu.render(&scene, &options)?;
    let on_cpu = Renderer::new(Backend::Cpu)?.render(&scene, &options)?;
    let d = glint::compare::diff(&on_gpu, &on_cpu);
    println!(
        "{}: {} pixels differ in some f32 bit, {} hit/miss, equal in every bit: {}",
        gpu.describe(),
        d.differing_bits,
        d.hit_miss,
        d.bit_exact()
    );
    Ok(())
}
