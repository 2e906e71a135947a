//! `akl calibrate`.

use super::print_json;
use crate::cli::CalibrateArgs;
use crate::exit::{CliError, CliResult};
use akl_learn::calibration::{Calibration, Motion, Separation};
use akl_learn::read_demo_file;
use akl_learn::teacher::calibration_demos;
use serde::Serialize;
use std::path::Path;

#[derive(Serialize)]
struct Report {
    output: String,
    source: String,
    calibration: Calibration,
    boundary_m: f64,
    switch_points: u32,
    separation: Separation,
}

pub(super) fn run(args: CalibrateArgs) -> CliResult {
    super::check_output(&args.output, "calibration")?;
    let (line, circle, source) = if args.simulate {
        let profile = super::profile(&args.profile)?;
        let (line, circle) = calibration_demos(&profile, args.seed).map_err(CliError::input)?;
        let source = format!("simulated teacher `{}`, seed {}", args.profile, args.seed);
        (Motion::of(&line), Motion::of(&circle), source)
    } else {
        // clap requires both files unless --simulate.
        let (Some(l), Some(c)) = (&args.line, &args.circle) else {
            return Err(CliError::input("give --line and --circle, or --simulate"));
        };
        let source = format!("line {}, circle {}", l.display(), c.display());
        (read_motion(l)?, read_motion(c)?, source)
    };
    let calibration = Calibration::fit(&line, &circle).map_err(CliError::input)?;
    calibration
        .save(&args.output)
        .map_err(|e| CliError::internal(format!("{}: {e}", args.output.display())))?;
    let report = Report {
        output: args.output.display().to_string(),
        source,
        calibration,
        boundary_m: calibration.boundary(),
        switch_points: calibration.switch_points(),
        separation: calibration.separation(&line, &circle),
    };
    if args.json {
        return print_json(&report);
    }
    let s = report.separation;
    println!("calibrated from {}", report.source);
    println!(
        "  logistic model:  β0 = {:.2}, β1 = {:.0} /m (a line error of {:.1} mm is the boundary)",
        calibration.beta0,
        calibration.beta1,
        report.boundary_m * 1e3
    );
    println!(
        "  energy tank:     T_d = {:.3}, T_s = {:.3} (switches after {} straight points of {:.0} cm)",
        calibration.tank_dissipation,
        calibration.tank_threshold,
        report.switch_points,
        calibration.filter_distance * 100.0
    );
    println!(
        "  on its own data: line {}/{} points constrained, circle {}/{} unconstrained",
        s.line_right, s.line_points, s.circle_right, s.circle_points
    );
    println!("wrote {}", report.output);
    Ok(())
}

fn read_motion(path: &Path) -> Result<Motion, CliError> {
    let loaded = read_demo_file(path).map_err(CliError::input)?;
    if let Some(t) = &loaded.truncation {
        eprintln!("warning: {}: {t}", path.display());
    }
    Ok(Motion::of(&loaded.demo))
}
