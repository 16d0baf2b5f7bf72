//! Aperture shapes from text (`ApertureShape::parse`) and from any mask
//! values, sampled, rasterised and turned into bokeh kernels: errors are
//! fine, panics, NaN densities and points off the square are not.
#![no_main]

use glam::Vec2;
use lenspath::bokeh::{Kernel, KernelSize};
use lenspath::camera::{Aperture, ApertureMask, ApertureShape};
use libfuzzer_sys::fuzz_target;

fn exercise(shape: &ApertureShape) {
    let Ok(aperture) = Aperture::new(shape) else { return };
    for k in 0..16u8 {
        let u = Vec2::new(f32::from(k) / 16.0, f32::from(k.wrapping_mul(7) % 16) / 16.0);
        let (p, pdf) = aperture.sample(u);
        assert!(pdf.is_finite() && pdf >= 0.0 && p.x.abs() <= 1.0 && p.y.abs() <= 1.0, "{p:?} {pdf}");
    }
    let _ = Kernel::from_aperture(&aperture, 9.5);
}

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(shape) = ApertureShape::parse(text) {
            exercise(&shape);
        }
    }
    // A mask: two size bytes, then one byte per value.
    if data.len() >= 2 {
        let (w, h) = (usize::from(data[0] % 32) + 1, usize::from(data[1] % 32) + 1);
        let values: Vec<f32> = data[2..].iter().take(w * h).map(|&b| f32::from(b) / 255.0).collect();
        if let Ok(mask) = ApertureMask::new(w, h, values.clone()) {
            exercise(&ApertureShape::Mask(std::sync::Arc::new(mask)));
        }
        if values.len() == w * h {
            let _ = Kernel::from_mask(w, h, &values, KernelSize::LongerSide(u32::from(data[0]) + 1));
        }
    }
});
