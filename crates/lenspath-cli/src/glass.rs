//! `lenspath glass`: a catalogue glass's indices at the Fraunhofer lines,
//! V_d, partial dispersion, internal transmittance and its nearest
//! equivalents from the other makers; or the glasses nearest to an (n_d,
//! V_d); and the Abbe diagram.

use std::path::PathBuf;

use clap::Args;
use lenspath::fs::write_text;
use lenspath::glass::{self, Glass, FRAUNHOFER_LINES};
use lenspath::lens::LensPrescription;
use lenspath::{Error, Result};

use crate::Outcome;

/// Options of `lenspath glass`.
#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("what").required(true).args(["name", "nd", "lens"])))]
pub struct GlassArgs {
    /// A catalogue glass: N-BK7, or maker:name (ohara:S-LAH59).
    name: Option<String>,
    /// Instead of a name: the n_d to find the nearest glasses to (with --vd).
    #[arg(long, requires = "vd", conflicts_with = "name")]
    nd: Option<f64>,
    /// The V_d to go with --nd.
    #[arg(long, requires = "nd")]
    vd: Option<f64>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Also draw the Abbe diagram (n_d against V_d of every catalogue glass) as SVG, this glass and --lens's glasses marked.
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// A lens whose glasses to list and mark on the plot (a shipped lens, .zmx, .json or table).
    #[arg(long, value_name = "LENS")]
    lens: Option<String>,
}

/// Where the internal transmittance is quoted, nm: the i, h, g, F, e, d and
/// C lines and 700 nm, as the makers' data sheets tabulate it.
const TRANSMITTANCE_NM: [f64; 8] = [365.01, 404.66, 435.83, 486.13, 546.07, 587.56, 656.27, 700.0];

/// Through what thicknesses, mm (the data sheets' two).
const TRANSMITTANCE_THICKNESS_MM: [f64; 2] = [10.0, 25.0];

/// `g`'s internal transmittance through each of [`TRANSMITTANCE_THICKNESS_MM`]
/// at `nm` (`None` where the catalogue gives no figure).
fn transmittances(g: &Glass, nm: f64) -> [Option<f64>; 2] {
    TRANSMITTANCE_THICKNESS_MM.map(|mm| g.internal_transmittance(nm, mm))
}

/// A glass as `--json` gives it.
fn describe(g: &Glass) -> serde_json::Value {
    let lines: serde_json::Map<String, serde_json::Value> = FRAUNHOFER_LINES
        .iter()
        .map(|(line, nm)| (format!("n_{line}"), g.dispersion.index(*nm).into()))
        .collect();
    serde_json::json!({
        "glass": format!("{}:{}", g.maker, g.name),
        "n_d": g.n_d,
        "v_d": g.v_d,
        "indices": lines,
        "partial_dispersion_g_f": g.partial_dispersion_g_f(),
        "formula_range_nm": [g.range_nm.0, g.range_nm.1],
        "glass_code": g.glass_code,
        "internal_transmittance": {
            "wavelength_nm": TRANSMITTANCE_NM,
            "thickness_mm": TRANSMITTANCE_THICKNESS_MM,
            "values": TRANSMITTANCE_NM.map(|nm| transmittances(g, nm)),
        },
    })
}

/// Runs `lenspath glass`.
pub fn run(args: GlassArgs) -> Result<Outcome> {
    let (subject, target): (Option<&Glass>, Option<(f64, f64)>) = match (&args.name, args.nd, args.vd) {
        (Some(name), _, _) => {
            let g = glass::find(name)?;
            (Some(g), Some((g.n_d, g.v_d)))
        }
        (None, Some(n_d), Some(v_d)) => {
            if !(n_d >= 1.0 && n_d.is_finite() && v_d > 0.0 && v_d.is_finite()) {
                return Err(Error::InvalidArgument(format!(
                    "--nd {n_d} --vd {v_d}: n_d must be at least 1 and V_d positive"
                )));
            }
            (None, Some((n_d, v_d)))
        }
        _ => (None, None),
    };
    // The lens's glasses: each glass's n_d / V_d (no V_d: a constant index), once.
    let mut lens_glasses: Vec<(String, f64, Option<f64>)> = Vec::new();
    if let Some(lens) = &args.lens {
        let prescription = LensPrescription::load(lens)?;
        for s in prescription.surfaces().iter().filter(|s| s.ior_d() > 1.0) {
            let (n_d, v_d) = (s.medium.n_d(), s.medium.abbe_number());
            let label = if v_d.is_finite() {
                format!("{n_d:.4}/{v_d:.1}")
            } else {
                format!("{n_d:.4}")
            };
            if !lens_glasses.iter().any(|(l, _, _)| *l == label) {
                lens_glasses.push((label, n_d, v_d.is_finite().then_some(v_d)));
            }
        }
    }
    let equivalents = target.map(|(n_d, v_d)| glass::nearest_of_each_maker(n_d, v_d));
    if let Some(path) = &args.plot {
        // A constant-index glass has no place on the diagram: it is listed only.
        let mut marked: Vec<(String, f64, f64)> = lens_glasses
            .iter()
            .filter_map(|(label, n_d, v_d)| v_d.map(|v| (label.clone(), *n_d, v)))
            .collect();
        if let Some((n_d, v_d)) = target {
            let label = subject.map_or(format!("{n_d}/{v_d}"), |g| g.name.to_string());
            marked.push((label, n_d, v_d));
        }
        write_text(path, &glass::abbe_diagram_svg(&marked))?;
    }
    if args.json {
        let json = serde_json::json!({
            "glass": subject.map(describe),
            "nearest_of_each_maker": equivalents.as_ref().map(|e| e.iter().map(|g| describe(g)).collect::<Vec<_>>()),
            "lens_glasses": lens_glasses.iter().map(|(l, n, v)| serde_json::json!({"label": l, "n_d": n, "v_d": v})).collect::<Vec<_>>(),
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&json).map_err(|e| Error::InvalidArgument(e.to_string()))?
        );
        return Ok(Outcome::Done);
    }
    if let Some(g) = subject {
        println!("{}:{}  n_d {:.5}  V_d {:.2}", g.maker, g.name, g.n_d, g.v_d);
        for (line, nm) in FRAUNHOFER_LINES {
            println!("  n_{line} ({nm} nm)  {:.6}", g.dispersion.index(nm));
        }
        println!("  partial dispersion P_g,F  {:.4}", g.partial_dispersion_g_f());
        println!("  formula valid {:.0}-{:.0} nm", g.range_nm.0, g.range_nm.1);
        println!("  internal transmittance   10 mm   25 mm");
        let figure = |t: Option<f64>| t.map_or("     -".to_string(), |t| format!("{t:>6.3}"));
        for nm in TRANSMITTANCE_NM {
            let [ten, twenty_five] = transmittances(g, nm);
            println!("    {nm:>6.1} nm             {}  {}", figure(ten), figure(twenty_five));
        }
    }
    if let (Some(equivalents), Some((n_d, v_d))) = (&equivalents, target) {
        println!("nearest to n_d {n_d:.4}, V_d {v_d:.2}, each maker:");
        for g in equivalents {
            println!(
                "  {:<22} n_d {:.5}  V_d {:>6.2}  P_g,F {:.4}",
                format!("{}:{}", g.maker, g.name),
                g.n_d,
                g.v_d,
                g.partial_dispersion_g_f()
            );
        }
    }
    if !lens_glasses.is_empty() {
        let labels: Vec<&str> = lens_glasses.iter().map(|(l, _, _)| l.as_str()).collect();
        println!("the lens's glasses (n_d/V_d): {}", labels.join(", "));
    }
    Ok(Outcome::Done)
}
