//! `lenspath glass`: a catalogue glass's indices at the Fraunhofer lines,
//! V_d, partial dispersion and its nearest equivalents from the other
//! makers; or the glasses nearest to an (n_d, V_d); and the Abbe diagram.

use std::path::PathBuf;

use clap::Args;
use lenspath::glass::{self, Glass, FRAUNHOFER_LINES};
use lenspath::io::write_text;
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
        "transmission": serde_json::Value::Null,
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
    // The lens's glasses: each glass row's name (or its n_d / V_d), once.
    let mut lens_glasses: Vec<(String, f64, f64)> = Vec::new();
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
                lens_glasses.push((label, n_d, if v_d.is_finite() { v_d } else { 90.0 }));
            }
        }
    }
    let equivalents = target.map(|(n_d, v_d)| glass::nearest_of_each_maker(n_d, v_d));
    if let Some(path) = &args.plot {
        let mut marked = lens_glasses.clone();
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
        println!(
            "  formula valid {:.0}-{:.0} nm; transmission: not in the catalogue",
            g.range_nm.0, g.range_nm.1
        );
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
