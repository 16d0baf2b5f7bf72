//! Bokeh as a post-process, on any image: convolution with a mask-shaped
//! kernel ([`convolve_planes`], shift-and-add or FFT), highlight lifting
//! for display-referred images ([`lift_highlights`]), and depth-aware lens
//! blur ([`depth_blur`]). docs/bokeh.md explains the methods. In the camera,
//! bokeh comes from [`crate::camera::ApertureShape`] instead.

mod convolve;
mod depth;
mod kernel;

pub use convolve::{
    check_blur_memory, choose_method, convolve_planes, convolve_rgb, direct, interleave_planes, rgb_planes, Edges,
    Method,
};
pub use depth::{depth_blur, CircleOfConfusion};
pub use kernel::{check_kernel_diameter, Kernel, KernelSize, MAX_KERNEL_SIDE_PX};

use crate::color::linear_to_srgb;

/// Lifts the highlights of a display-referred image (linear RGB, 3 floats a
/// pixel) before blurring: clipped at 1, its small lights would otherwise
/// never bloom into bright discs. A pixel whose brightest channel, as stored
/// (sRGB-encoded), exceeds `threshold` is scaled by 1 + (`gain` − 1)·t²,
/// t = (encoded − threshold)/(1 − threshold), so the lift starts smoothly.
pub fn lift_highlights(rgb: &mut [f32], gain: f32, threshold: f32) {
    for pixel in rgb.chunks_exact_mut(3) {
        let brightest = linear_to_srgb(pixel[0].max(pixel[1]).max(pixel[2]));
        if brightest > threshold {
            let t = ((brightest - threshold) / (1.0 - threshold).max(1e-6)).min(1.0);
            let scale = 1.0 + (gain - 1.0) * t * t;
            for v in pixel.iter_mut() {
                *v *= scale;
            }
        }
    }
}
