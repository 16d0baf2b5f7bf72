//! `lenspath bokeh`: blur an image with a mask-shaped kernel.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use lenspath::bokeh::{
    check_blur_memory, check_kernel_diameter, choose_method, convolve_planes, depth_blur, interleave_planes,
    lift_highlights, rgb_planes, CircleOfConfusion, Edges, Kernel, KernelSize, Method, MAX_KERNEL_SIDE_PX,
};
use lenspath::camera::{Aperture, ApertureShape};
use lenspath::io::exr::HeaderValue;
use lenspath::io::image::{check_output_path, read_exr, read_gray, read_image, write_image_with_header, ImageHeader};
use lenspath::lens::{LensPrescription, LensSystem};
use lenspath::names::Named;
use lenspath::{Error, Result};

use crate::flags::named;
use crate::Outcome;

/// Kernel size: pixels of its longer side, or the image's size.
#[derive(Clone, Copy, Debug)]
pub enum SizeArg {
    Pixels(u32),
    Full,
}

fn parse_size(s: &str) -> std::result::Result<SizeArg, String> {
    if s.eq_ignore_ascii_case("full") {
        return Ok(SizeArg::Full);
    }
    match s.parse::<u32>() {
        Ok(n) if (1..=MAX_KERNEL_SIDE_PX).contains(&n) => Ok(SizeArg::Pixels(n)),
        _ => Err(format!(
            "expected a size in pixels (1 to {MAX_KERNEL_SIDE_PX}) or 'full', got '{s}'"
        )),
    }
}

/// Options of `lenspath bokeh`.
#[derive(Args, Debug)]
pub struct BokehArgs {
    /// Image to blur: PNG or JPEG (sRGB, linearised before blurring and encoded again after) or EXR (linear).
    image: PathBuf,
    /// The blur's shape: a grayscale image (PNG, JPEG or EXR; white is open), or circle,
    /// blades:N[:ROTATION_DEG[:CURVATURE]] or star:N[:INNER_RATIO[:ROTATION_DEG]].
    #[arg(long)]
    mask: String,
    /// Output image: .png (sRGB) or .exr (linear).
    #[arg(long)]
    out: PathBuf,
    /// Kernel size: its longer side in pixels, or 'full' to resize it to the image's width and
    /// height [default: a mask image's own size; 64 for a shape].
    #[arg(long, value_parser = parse_size)]
    size: Option<SizeArg>,
    /// How to convolve: auto (whichever is faster for this image and kernel), direct
    /// (shift-and-add over the open mask pixels, the reference) or fft (with zero padding).
    #[arg(long, value_parser = named::<Method>(), default_value = Method::default().name())]
    method: Method,
    /// What lies beyond the image's edges: renormalize (divide by the share of the kernel inside
    /// the image: no dark border) or black (OpenCV's BORDER_CONSTANT: the border darkens).
    #[arg(long, value_parser = named::<Edges>(), default_value = Edges::default().name())]
    edges: Edges,
    /// PNG or JPEG input: multiply its highlights by up to GAIN before blurring, so small
    /// lights bloom into bright discs as they would from a linear image.
    #[arg(long, value_name = "GAIN")]
    highlights: Option<f32>,
    /// With --highlights: the stored (sRGB) brightness, 0 to 1, where the lift starts.
    #[arg(long, value_name = "T", default_value_t = 0.9)]
    threshold: f32,
    #[command(flatten)]
    depth: DepthFlags,
}

/// Depth-aware lens blur: where the depths come from and the lens that blurs.
#[derive(Args, Debug)]
struct DepthFlags {
    /// Depth-aware blur with these depths: an EXR's Z channel (or its only channel), distances
    /// along the view axis in scene units. Without it, an EXR input's own Z channel is used when
    /// --focus-distance is given.
    #[arg(long, value_name = "DEPTH.exr")]
    depth: Option<PathBuf>,
    /// Depth-aware blur: the distance in focus, scene units.
    #[arg(long, value_name = "D")]
    focus_distance: Option<f64>,
    /// Depth-aware blur with a thin lens: its f-number (with --focal-length), or stop --lens down.
    #[arg(long, value_name = "N")]
    fstop: Option<f64>,
    /// Depth-aware blur with a thin lens of this focal length, mm.
    #[arg(long, value_name = "MM", conflicts_with = "lens")]
    focal_length: Option<f64>,
    /// Depth-aware blur with the first-order (paraxial) focal length and f-number of this lens.
    #[arg(long, value_name = "NAME|FILE")]
    lens: Option<String>,
    /// Depth-aware blur with lenspath's thin-lens camera: its aperture radius, scene units (with --fov).
    #[arg(long, value_name = "R", conflicts_with_all = ["lens", "focal_length"])]
    aperture_radius: Option<f64>,
    /// With --aperture-radius: the camera's vertical field of view, degrees.
    #[arg(long, value_name = "DEG", requires = "aperture_radius")]
    fov: Option<f64>,
    /// Width of the sensor the image covers, mm (for --focal-length and --lens).
    #[arg(long, value_name = "MM", default_value_t = lenspath::camera::DEFAULT_SENSOR_WIDTH_MM)]
    sensor_width: f64,
    /// Metres per scene unit of the depths and --focus-distance (for --focal-length and --lens).
    #[arg(long, value_name = "M", default_value_t = lenspath::camera::DEFAULT_SCENE_UNIT_M)]
    scene_unit: f64,
}

impl DepthFlags {
    /// The circle of confusion the flags describe for a `width`×`height` image,
    /// or `None` without --focus-distance.
    fn circle_of_confusion(&self, width: u32, height: u32) -> Result<Option<CircleOfConfusion>> {
        let Some(focus) = self.focus_distance else {
            if self.depth.is_some() {
                return Err(Error::InvalidArgument("--depth needs --focus-distance".into()));
            }
            return Ok(None);
        };
        if let Some(radius) = self.aperture_radius {
            let fov = self
                .fov
                .ok_or_else(|| Error::InvalidArgument("--aperture-radius needs --fov".into()))?;
            return CircleOfConfusion::thin_lens_camera(radius, focus, fov, height).map(Some);
        }
        let (focal_length, f_number) = match (&self.lens, self.focal_length, self.fstop) {
            (Some(name), _, stop) => {
                let system = LensSystem::new(&LensPrescription::load(name)?);
                let paraxial = system.paraxial()?;
                (paraxial.effective_focal_length_mm, stop.unwrap_or(paraxial.f_number))
            }
            (None, Some(f), Some(n)) => (f, n),
            _ => {
                return Err(Error::InvalidArgument(
                    "--focus-distance needs a lens: --fstop N --focal-length MM, --lens NAME, or --aperture-radius R --fov DEG"
                        .into(),
                ))
            }
        };
        CircleOfConfusion::thin_lens_in_scene_units(
            focal_length,
            f_number,
            focus,
            self.scene_unit,
            self.sensor_width,
            width,
        )
        .map(Some)
    }
}

/// Runs `lenspath bokeh`.
pub fn run(args: BokehArgs) -> Result<Outcome> {
    check_output_path(&args.out)?;
    if let Some(gain) = args.highlights {
        if !(gain >= 1.0 && gain.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "--highlights must be a gain of 1 or more, got {gain}"
            )));
        }
    }
    if !(0.0..1.0).contains(&args.threshold) {
        return Err(Error::InvalidArgument(format!(
            "--threshold must be at least 0 and below 1, got {}",
            args.threshold
        )));
    }
    let mut input = read_image(&args.image)?;
    let (width, height) = (input.image.width as usize, input.image.height as usize);
    let coc = args.depth.circle_of_confusion(input.image.width, input.image.height)?;
    let size = match args.size {
        None => KernelSize::Native,
        Some(SizeArg::Pixels(n)) => KernelSize::LongerSide(n),
        Some(SizeArg::Full) => KernelSize::Exactly(width as u32, height as u32),
    };
    if let Some(gain) = args.highlights {
        if !input.display_referred {
            return Err(Error::InvalidArgument(format!(
                "--highlights is for PNG or JPEG input; {} is linear and keeps its highlights",
                args.image.display()
            )));
        }
        lift_highlights(&mut input.image.rgb, gain, args.threshold);
    }
    if let Some(coc) = coc {
        if args.size.is_some() {
            return Err(Error::InvalidArgument(
                "--size is for a uniform blur; with depths each pixel's blur size comes from the lens".into(),
            ));
        }
        return run_depth_blur(&args, input.image, &blurred_header(input.header, &args), &coc);
    }
    let kernel = load_kernel(&args.mask, size)?;
    let method = match args.method {
        Method::Auto => choose_method(width, height, &kernel),
        chosen => chosen,
    };
    check_blur_memory(width, height, &kernel, method)?;
    let edges = args.edges;
    let mut output = input.image;
    // Timed: the convolution alone, not the change of pixel layout around it.
    let planes = rgb_planes(&output.rgb);
    let start = Instant::now();
    let blurred = convolve_planes(&planes, width, height, &kernel, method, edges);
    let seconds = start.elapsed().as_secs_f64();
    interleave_planes(&blurred, &mut output.rgb);
    write_image_with_header(&args.out, &output, 0.0, &blurred_header(input.header, &args))?;
    println!(
        "blurred {width}x{height} with a {}x{} kernel by {} in {:.1} ms -> {}",
        kernel.width,
        kernel.height,
        if method == Method::Direct {
            "shift-and-add"
        } else {
            "FFT"
        },
        seconds * 1e3,
        args.out.display()
    );
    Ok(Outcome::Done)
}

/// Depth-aware blur of `image` and the report line.
fn run_depth_blur(
    args: &BokehArgs,
    mut image: lenspath::film::Image,
    header: &ImageHeader,
    coc: &CircleOfConfusion,
) -> Result<Outcome> {
    let depth = match &args.depth.depth {
        Some(path) => {
            let map = read_exr(path)?;
            if (map.width, map.height) != (image.width, image.height) {
                return Err(Error::Parse {
                    kind: lenspath::FileKind::Image,
                    path: path.clone(),
                    message: format!(
                        "the depth map is {}x{}, the image {}x{}",
                        map.width, map.height, image.width, image.height
                    ),
                });
            }
            // A Z channel if there is one, else the (gray) image itself.
            if map.depth.iter().any(|z| z.is_finite()) {
                map.depth
            } else {
                map.rgb.iter().step_by(3).copied().collect()
            }
        }
        None if image.depth.iter().any(|z| z.is_finite()) => image.depth.clone(),
        None => {
            return Err(Error::InvalidArgument(format!(
                "--focus-distance needs depths: {} has no Z channel; give --depth DEPTH.exr",
                args.image.display()
            )))
        }
    };
    let aperture = Aperture::new(&load_shape(&args.mask)?)?;
    let (width, height) = (image.width as usize, image.height as usize);
    let start = Instant::now();
    let blurred = depth_blur(&image.rgb, &depth, width, height, coc, &aperture)?;
    let seconds = start.elapsed().as_secs_f64();
    let largest = depth
        .iter()
        .map(|&z| coc.diameter_px(f64::from(z)).abs())
        .fold(0.0, f64::max);
    image.rgb = blurred;
    write_image_with_header(&args.out, &image, 0.0, header)?;
    println!(
        "blurred {width}x{height} by depth (circles of confusion up to {largest:.1} px) in {:.1} ms -> {}",
        seconds * 1e3,
        args.out.display()
    );
    Ok(Outcome::Done)
}

/// The input's header (an EXR's: camera, lens, settings), carried over to the
/// blurred image with the blur's mask under `lenspath/bokehMask`.
fn blurred_header(mut header: ImageHeader, args: &BokehArgs) -> ImageHeader {
    header
        .attributes
        .insert("lenspath/bokehMask".into(), HeaderValue::Text(args.mask.clone()));
    header
}

/// The shape of `--mask`: an image file, or else a named shape.
fn load_shape(mask: &str) -> Result<ApertureShape> {
    if PathBuf::from(mask).exists() {
        return lenspath::io::image::read_aperture_mask(std::path::Path::new(mask));
    }
    ApertureShape::parse(mask).map_err(|e| {
        Error::InvalidArgument(format!(
            "--mask '{mask}': no such file, and not a shape ({})",
            e.to_string().rsplit("; ").next().unwrap_or_default()
        ))
    })
}

/// The kernel of `--mask`: an image file, or else a named shape.
fn load_kernel(mask: &str, size: KernelSize) -> Result<Kernel> {
    let path = PathBuf::from(mask);
    if path.exists() {
        let (w, h, values) = read_gray(&path)?;
        return Kernel::from_mask(w, h, &values, size).map_err(|e| Error::Parse {
            kind: lenspath::FileKind::Image,
            path,
            message: e.to_string(),
        });
    }
    let shape = load_shape(mask)?;
    let side = match size {
        KernelSize::LongerSide(n) => n as usize,
        KernelSize::Exactly(w, h) => w.max(h) as usize,
        KernelSize::Native => 64,
    };
    check_kernel_diameter(side as f64)?;
    let raster = Aperture::new(&shape)?.rasterize(side, side, 1.0);
    Kernel::from_mask(side, side, &raster, size)
}
