//! The bokeh convolution against OpenCV's `filter2D` (with the kernel
//! flipped, since OpenCV correlates, and black borders), when Python with
//! opencv-python and numpy is there: `python3`, or the interpreter named by
//! `LENSPATH_PYTHON` (bench/bokeh_peers.py makes one). Skipped, saying so,
//! otherwise.

use std::process::Command;

use lenspath::bokeh::{convolve_rgb, Edges, Kernel, KernelSize, Method};
use lenspath::sampling::Rng;

fn python() -> String {
    std::env::var("LENSPATH_PYTHON").unwrap_or_else(|_| "python3".into())
}

fn write_f32(path: &std::path::Path, values: &[f32]) {
    std::fs::write(path, values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()).unwrap();
}

#[test]
fn convolution_matches_opencv_filter2d() {
    let has_opencv = Command::new(python())
        .args(["-c", "import cv2, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_opencv {
        eprintln!("skipping: no Python with opencv-python and numpy (set LENSPATH_PYTHON)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng::new(9);
    for (w, h, kw, kh) in [(97usize, 61usize, 13usize, 8usize), (64, 48, 64, 48), (40, 30, 7, 7)] {
        let rgb: Vec<f32> = (0..w * h * 3).map(|_| rng.uniform()).collect();
        let mask: Vec<f32> = (0..kw * kh)
            .map(|_| if rng.uniform() < 0.3 { 0.0 } else { rng.uniform() })
            .collect();
        let kernel = Kernel::from_mask(kw, kh, &mask, KernelSize::Native).unwrap();
        write_f32(&dir.path().join("image.f32"), &rgb);
        write_f32(&dir.path().join("kernel.f32"), &kernel.weights);
        let (cx, cy) = kernel.centre();
        let script = format!(
            "import cv2, numpy as np\n\
             d = r'{dir}'\n\
             img = np.fromfile(d + '/image.f32', dtype='<f4').reshape({h}, {w}, 3)\n\
             k = np.fromfile(d + '/kernel.f32', dtype='<f4').reshape({kh}, {kw})\n\
             out = cv2.filter2D(img, -1, k[::-1, ::-1].copy(), anchor=({ax}, {ay}), borderType=cv2.BORDER_CONSTANT)\n\
             out.astype('<f4').tofile(d + '/opencv.f32')\n",
            dir = dir.path().display(),
            ax = kw - 1 - cx,
            ay = kh - 1 - cy,
        );
        let o = Command::new(python()).args(["-c", &script]).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(dir.path().join("opencv.f32")).unwrap();
        let opencv: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        for method in [Method::Direct, Method::Fft] {
            let mut ours = rgb.clone();
            convolve_rgb(&mut ours, w, h, &kernel, method, Edges::Black);
            let peak = opencv.iter().fold(0f32, |m, v| m.max(v.abs()));
            let worst = (0..w * h * 3).map(|i| (ours[i] - opencv[i]).abs()).fold(0f32, f32::max);
            assert!(
                worst <= 1e-5 * peak,
                "{w}x{h} * {kw}x{kh} by {method:?}: off OpenCV by {worst} (peak {peak})"
            );
        }
    }
}
