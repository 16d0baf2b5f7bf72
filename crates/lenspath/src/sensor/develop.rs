//! Developing a raw frame into an image, as a raw converter does (dcraw's
//! order; Adobe DNG Specification 1.4, ch. 6, for the colour model):
//!
//! 1. black level off, scaled so the white level is 1;
//! 2. white balance: each channel divided by the as-shot neutral, so the
//!    balanced-for white reads 1 in every channel, and clipped at 1, where
//!    the first channel saturates (otherwise a blown highlight, clipped in
//!    green, turns magenta once red and blue are scaled up);
//! 3. demosaicking ([`Demosaic`]);
//! 4. the colour matrix back to CIE XYZ, white to D65 white, then linear
//!    sRGB: `ColorMatrix1` maps XYZ to the camera's channels under D65, so
//!    the balanced channels times D65's neutral are the camera's reading of
//!    the scene as if lit by D65 (a von Kries adaptation in the camera's
//!    space, as dcraw's multipliers);
//! 5. a tone curve ([`ToneCurve`]).
//!
//! A surface that reflects the balanced-for light evenly at the white level
//! develops to linear sRGB white (1, 1, 1).

use glam::{DMat3, DVec3, Mat3, Vec3};
use rayon::prelude::*;

use super::{Cfa, RawFrame};
use crate::film::Image;
use crate::names::Named;
use crate::spectrum::cie;

/// How the mosaic's missing channels are filled in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Demosaic {
    /// Each missing channel the mean of the nearest pixels that read it.
    Bilinear,
    /// Malvar, He and Cutler, "High-quality linear interpolation for
    /// demosaicing of Bayer-patterned color images", ICASSP 2004: bilinear
    /// corrected by the Laplacian of the channel the pixel reads (5 × 5
    /// kernels; about 5.5 dB better than bilinear on the Kodak set). The
    /// default: the best linear method.
    #[default]
    MalvarHeCutler,
}

impl Named for Demosaic {
    const WHAT: &'static str = "demosaicking method";
    const NAMED: &'static [(Demosaic, &'static str)] = &[
        (Demosaic::Bilinear, "bilinear"),
        (Demosaic::MalvarHeCutler, "mhc"),
        (Demosaic::MalvarHeCutler, "malvar"),
    ];
}

/// The curve from linear sRGB to the developed image's values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneCurve {
    /// None: the image stays linear (its file's encoding, such as the sRGB
    /// transfer function of a PNG, is the writer's). The default, so that
    /// developed values stay proportional to the light, as a render's are.
    #[default]
    Linear,
    /// A filmic shoulder and toe: Narkowicz's fit of the ACES reference
    /// rendering transform ("ACES Filmic Tone Mapping Curve", 2016), per
    /// channel; 1 maps to 0.80 and highlights roll off towards 1.
    Filmic,
}

impl Named for ToneCurve {
    const WHAT: &'static str = "tone curve";
    const NAMED: &'static [(ToneCurve, &'static str)] = &[(ToneCurve::Linear, "linear"), (ToneCurve::Filmic, "filmic")];
}

impl ToneCurve {
    /// The curve at linear value `x`.
    #[inline]
    pub fn apply(self, x: f32) -> f32 {
        match self {
            ToneCurve::Linear => x,
            ToneCurve::Filmic => {
                let x = x.max(0.0);
                (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).min(1.0)
            }
        }
    }
}

/// How a raw frame is developed (by default, each method's default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Development {
    /// The demosaicking method.
    pub demosaic: Demosaic,
    /// The tone curve.
    pub tone_curve: ToneCurve,
}

/// `frame` developed `how`, linear sRGB 1 at the white level before the
/// tone curve.
pub fn develop(frame: &RawFrame, how: &Development) -> Image {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let balanced = Balanced::new(frame);
    let mut rgb = vec![0f32; 3 * w * h];
    let to_srgb = camera_to_srgb(frame);
    let curve = how.tone_curve;
    rgb.par_chunks_mut(3 * w.max(1)).enumerate().for_each(|(y, row)| {
        let rows: [&[f32]; 5] = std::array::from_fn(|k| balanced.row(y + k));
        let channels = [frame.cfa.channel(0, y as u32), frame.cfa.channel(1, y as u32)];
        for (x, out) in row.chunks_exact_mut(3).enumerate() {
            let around = Neighbourhood::of(&rows, x + BORDER);
            let srgb = if frame.cfa == Cfa::Mono {
                // One channel: grey, its luminance.
                Vec3::splat(around.centre)
            } else {
                to_srgb * how.demosaic.channels(&around, channels[x % 2], channels[1 - x % 2])
            };
            out.copy_from_slice(&srgb.to_array().map(|v| curve.apply(v)));
        }
    });
    Image {
        width: frame.width,
        height: frame.height,
        rgb,
        depth: vec![f32::INFINITY; w * h],
        spp_min: 0,
        spp_requested: 0,
    }
}

/// Step 4: balanced camera channels to linear sRGB. D65 white lands on
/// (1, 1, 1) exactly (the neutral is the matrix's own D65 reading).
fn camera_to_srgb(frame: &RawFrame) -> Mat3 {
    let tables = cie::tables();
    let white = tables.white_xyz.as_dvec3();
    let d65_neutral = frame.xyz_to_camera * white;
    let camera_to_xyz = frame.xyz_to_camera.inverse() * DMat3::from_diagonal(d65_neutral);
    let xyz_to_srgb = tables.rgb_to_xyz_f64().inverse();
    let m = xyz_to_srgb * camera_to_xyz;
    // Exact white: any rounding in the tables' white point is taken out.
    let scale = m * DVec3::ONE;
    (DMat3::from_diagonal(1.0 / scale) * m).as_mat3()
}

/// Pixels on every side of the balanced mosaic, mirrored about the edge
/// pixels (which keeps the colour filter's phase), so every 5 × 5 kernel
/// reads inside it.
const BORDER: usize = 2;

/// Steps 1 and 2 over the whole mosaic: each pixel's channel over the black
/// level, scaled to the white level, divided by the as-shot neutral,
/// clipped at 1 (a monochrome sensor clips where its one channel does);
/// with a mirrored border.
struct Balanced {
    values: Vec<f32>,
    stride: usize,
}

impl Balanced {
    fn new(frame: &RawFrame) -> Balanced {
        let (w, h) = (frame.width as usize, frame.height as usize);
        let black = frame.black_level_dn as f32;
        let range = (frame.white_level_dn - frame.black_level_dn) as f32;
        let gain = (1.0 / frame.as_shot_neutral).as_vec3() / range;
        let clip = if frame.cfa == Cfa::Mono { f32::INFINITY } else { 1.0 };
        let mirror = |i: usize, n: usize| -> usize {
            let i = i as isize - BORDER as isize;
            let n = n as isize;
            let m = if i < 0 {
                -i
            } else if i >= n {
                2 * (n - 1) - i
            } else {
                i
            };
            m.clamp(0, n - 1) as usize
        };
        let stride = w + 2 * BORDER;
        let mut values = vec![0f32; stride * (h + 2 * BORDER)];
        values.par_chunks_mut(stride).enumerate().for_each(|(py, row)| {
            let y = mirror(py, h);
            let dn = &frame.dn[y * w..(y + 1) * w];
            let gains = [
                gain[frame.cfa.channel(0, y as u32)],
                gain[frame.cfa.channel(1, y as u32)],
            ];
            for (px, v) in row.iter_mut().enumerate() {
                let x = mirror(px, w);
                *v = ((f32::from(dn[x]) - black) * gains[x % 2]).min(clip);
            }
        });
        Balanced { values, stride }
    }

    /// Padded row `py` (image row `py` − 2).
    fn row(&self, py: usize) -> &[f32] {
        &self.values[py * self.stride..(py + 1) * self.stride]
    }
}

/// What the demosaicking kernels read around a pixel: its value and the
/// sums of its neighbours by place.
struct Neighbourhood {
    centre: f32,
    /// Left and right.
    row_1: f32,
    /// Above and below.
    column_1: f32,
    /// Two to the left and right.
    row_2: f32,
    /// Two above and below.
    column_2: f32,
    /// The four diagonal neighbours.
    diagonal: f32,
}

impl Neighbourhood {
    /// Around column `px` of the centre one of five padded `rows`.
    #[inline(always)]
    fn of(rows: &[&[f32]; 5], px: usize) -> Neighbourhood {
        let [r0, r1, r2, r3, r4] = rows;
        Neighbourhood {
            centre: r2[px],
            row_1: r2[px - 1] + r2[px + 1],
            column_1: r1[px] + r3[px],
            row_2: r2[px - 2] + r2[px + 2],
            column_2: r0[px] + r4[px],
            diagonal: r1[px - 1] + r1[px + 1] + r3[px - 1] + r3[px + 1],
        }
    }
}

impl Demosaic {
    /// The camera channels at a pixel reading channel `own` whose row
    /// neighbours read `in_row`, from its neighbourhood.
    #[inline(always)]
    fn channels(self, n: &Neighbourhood, own: usize, in_row: usize) -> Vec3 {
        let c = n.centre;
        // Green at a red or blue pixel; the other of red and blue there;
        // red or blue at a green pixel from its row, or from its column.
        let [green, diagonal, row, column] = match self {
            Demosaic::Bilinear => [
                0.25 * (n.row_1 + n.column_1),
                0.25 * n.diagonal,
                0.5 * n.row_1,
                0.5 * n.column_1,
            ],
            // Malvar, He and Cutler's Fig. 2 kernels, over 8.
            Demosaic::MalvarHeCutler => [
                (4.0 * c + 2.0 * (n.row_1 + n.column_1) - (n.row_2 + n.column_2)) / 8.0,
                (6.0 * c + 2.0 * n.diagonal - 1.5 * (n.row_2 + n.column_2)) / 8.0,
                (5.0 * c + 4.0 * n.row_1 - n.row_2 - n.diagonal + 0.5 * n.column_2) / 8.0,
                (5.0 * c + 4.0 * n.column_1 - n.column_2 - n.diagonal + 0.5 * n.row_2) / 8.0,
            ],
        };
        let mut rgb = [0f32; 3];
        rgb[own] = c;
        if own == 1 {
            rgb[in_row] = row;
            rgb[2 - in_row] = column;
        } else {
            rgb[1] = green;
            rgb[2 - own] = diagonal;
        }
        Vec3::from_array(rgb)
    }
}
