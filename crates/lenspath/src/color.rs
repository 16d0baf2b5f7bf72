//! Colour encodings: the sRGB transfer function both ways, and a linear
//! image as 8-bit sRGB (what PNG and JPEG output and the viewer's frames
//! hold); CIELAB and the CIEDE2000 colour difference, how a developed image
//! is compared with a chart's published colours. The image formats
//! themselves are in `io::image`.

use glam::DVec3;

/// Relative luminance Y of a linear sRGB colour: the Y row of the sRGB
/// (Rec. 709 primaries, D65) to CIE XYZ matrix, IEC 61966-2-1.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// The sRGB transfer function (IEC 61966-2-1) from linear to encoded.
pub fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x.max(0.0)
    } else {
        1.055 * x.min(1.0).powf(1.0 / 2.4) - 0.055
    }
}

/// The sRGB transfer function (IEC 61966-2-1) from encoded to linear.
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// 8-bit sRGB bytes of linear values (an image's RGB) after an exposure of
/// `exposure` stops.
pub fn to_srgb8(linear: &[f32], exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    linear
        .iter()
        .map(|&v| (linear_to_srgb(v * scale) * 255.0 + 0.5).clamp(0.0, 255.0) as u8)
        .collect()
}

/// CIE 1976 L*a*b* of `xyz` relative to the white `white_xyz` (CIE 15:2004,
/// §8.2.1).
pub fn xyz_to_lab(xyz: DVec3, white_xyz: DVec3) -> DVec3 {
    const DELTA: f64 = 6.0 / 29.0;
    let f = |t: f64| {
        if t > DELTA.powi(3) {
            t.cbrt()
        } else {
            t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
        }
    };
    let (fx, fy, fz) = (f(xyz.x / white_xyz.x), f(xyz.y / white_xyz.y), f(xyz.z / white_xyz.z));
    DVec3::new(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz))
}

/// The CIEDE2000 colour difference of two L*a*b* colours (CIE 142-2001;
/// the formulas as Sharma, Wu and Dalal, "The CIEDE2000 color-difference
/// formula: implementation notes", Color Res. Appl. 30, 2005, eqs. 1-22,
/// with kL = kC = kH = 1).
pub fn delta_e_2000(lab1: DVec3, lab2: DVec3) -> f64 {
    let pow7 = |x: f64| x.powi(7);
    let twenty_five_7 = pow7(25.0);
    let c_bar = 0.5 * (lab1.y.hypot(lab1.z) + lab2.y.hypot(lab2.z));
    let g = 0.5 * (1.0 - (pow7(c_bar) / (pow7(c_bar) + twenty_five_7)).sqrt());
    // a' , C', h' (degrees in [0, 360); 0 for a neutral).
    let prime = |lab: DVec3| {
        let a = (1.0 + g) * lab.y;
        let c = a.hypot(lab.z);
        let h = if a == 0.0 && lab.z == 0.0 {
            0.0
        } else {
            lab.z.atan2(a).to_degrees().rem_euclid(360.0)
        };
        (c, h)
    };
    let ((c1, h1), (c2, h2)) = (prime(lab1), prime(lab2));
    let delta_l = lab2.x - lab1.x;
    let delta_c = c2 - c1;
    let delta_h_angle = if c1 * c2 == 0.0 {
        0.0
    } else {
        let d = h2 - h1;
        if d > 180.0 {
            d - 360.0
        } else if d < -180.0 {
            d + 360.0
        } else {
            d
        }
    };
    let delta_h = 2.0 * (c1 * c2).sqrt() * (0.5 * delta_h_angle).to_radians().sin();
    let l_bar = 0.5 * (lab1.x + lab2.x);
    let c_bar_prime = 0.5 * (c1 + c2);
    let h_bar = if c1 * c2 == 0.0 {
        h1 + h2
    } else if (h1 - h2).abs() <= 180.0 {
        0.5 * (h1 + h2)
    } else if h1 + h2 < 360.0 {
        0.5 * (h1 + h2 + 360.0)
    } else {
        0.5 * (h1 + h2 - 360.0)
    };
    let cos_deg = |d: f64| d.to_radians().cos();
    let t = 1.0 - 0.17 * cos_deg(h_bar - 30.0) + 0.24 * cos_deg(2.0 * h_bar) + 0.32 * cos_deg(3.0 * h_bar + 6.0)
        - 0.20 * cos_deg(4.0 * h_bar - 63.0);
    let delta_theta = 30.0 * (-((h_bar - 275.0) / 25.0).powi(2)).exp();
    let r_c = 2.0 * (pow7(c_bar_prime) / (pow7(c_bar_prime) + twenty_five_7)).sqrt();
    let l50 = (l_bar - 50.0).powi(2);
    let s_l = 1.0 + 0.015 * l50 / (20.0 + l50).sqrt();
    let s_c = 1.0 + 0.045 * c_bar_prime;
    let s_h = 1.0 + 0.015 * c_bar_prime * t;
    let r_t = -(2.0 * delta_theta).to_radians().sin() * r_c;
    let (l, c, h) = (delta_l / s_l, delta_c / s_c, delta_h / s_h);
    (l * l + c * c + h * h + r_t * c * h).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ciede2000_gives_sharmas_published_differences() {
        // Sharma, Wu and Dalal 2005, Table 1: pairs chosen to exercise each
        // term (hue wrap-around, the blue region's rotation, near-neutrals).
        let pairs = [
            ([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], 2.0425),
            ([50.0, -1.3802, -84.2814], [50.0, 0.0, -82.7485], 1.0000),
            ([50.0, 0.0, 0.0], [50.0, -1.0, 2.0], 2.3669),
            ([50.0, 2.49, -0.001], [50.0, -2.49, 0.0009], 7.1792),
            ([50.0, 2.49, -0.001], [50.0, -2.49, 0.0011], 7.2195),
            ([50.0, -0.001, 2.49], [50.0, 0.0009, -2.49], 4.8045),
            ([50.0, 2.5, 0.0], [73.0, 25.0, -18.0], 27.1492),
            ([50.0, 2.5, 0.0], [56.0, -27.0, -3.0], 31.9030),
            ([60.2574, -34.0099, 36.2677], [60.4626, -34.1751, 39.4387], 1.2644),
            ([22.7233, 20.0904, -46.6940], [23.0331, 14.9730, -42.5619], 2.0373),
            ([90.8027, -2.0831, 1.4410], [91.1528, -1.6435, 0.0447], 1.4441),
            ([2.0776, 0.0795, -1.1350], [0.9033, -0.0636, -0.5514], 0.9082),
        ];
        for (a, b, expected) in pairs {
            let (a, b) = (DVec3::from_array(a), DVec3::from_array(b));
            for (x, y) in [(a, b), (b, a)] {
                let got = delta_e_2000(x, y);
                assert!((got - expected).abs() < 1e-4, "{x} {y}: {got} for {expected}");
            }
        }
        assert_eq!(
            delta_e_2000(DVec3::new(52.0, 10.0, -30.0), DVec3::new(52.0, 10.0, -30.0)),
            0.0
        );
    }

    #[test]
    fn lab_of_the_white_is_100_and_of_srgb_red_is_the_published_one() {
        let white = DVec3::new(0.950_47, 1.0, 1.088_83);
        assert!((xyz_to_lab(white, white) - DVec3::new(100.0, 0.0, 0.0)).length() < 1e-12);
        // sRGB red (the XYZ of IEC 61966-2-1's primary, D65 white): L*a*b*
        // 53.2408, 80.0925, 67.2032 (Lindbloom's colour calculator).
        let red = xyz_to_lab(DVec3::new(0.412_456_4, 0.212_672_9, 0.019_333_9), white);
        assert!(
            (red - DVec3::new(53.2408, 80.0925, 67.2032)).abs().max_element() < 0.005,
            "{red}"
        );
    }
}
