//! `akl demo`: teach with the simulated teacher, learn with AKL, execute with randomized
//! objects; each stage's result and files.

use super::execute::{execute, jobs, print_executed, verdict, Execution};
use super::robot::load as load_robot;
use super::spec::keyframe_table;
use super::teach::{
    learn_and_save, print_learned, print_recorded, teach_simulated, SimulatedTeaching,
};
use crate::cli::{DemoArgs, RobotArg};
use crate::exit::{CliError, CliResult};
use crate::table::Table;
use akl_exec::ExecOptions;
use akl_learn::calibration::Calibration;
use akl_learn::{score, Tolerance};

pub(super) fn run(args: DemoArgs) -> CliResult {
    if args.trials == 0 {
        return Err(CliError::input("--trials: needs at least one trial"));
    }
    // Refused before any teaching is done.
    jobs(args.jobs)?;
    if args.out.exists() && !args.out.is_dir() {
        return Err(CliError::input(format!(
            "{}: --out must be a folder",
            args.out.display()
        )));
    }
    let task = super::load_task(&args.task)?;
    let robot = load_robot(&RobotArg {
        robot: None,
        package_path: Vec::new(),
    })?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::input(format!("{}: {e}", args.out.display())))?;
    let demo_path = args.out.join("demo.mcap");
    let spec_path = args.out.join("spec.json");
    let report_path = args.out.join("report.json");
    let trace_path = args.out.join("trace.mcap");

    let calibration = Calibration::default();
    let teaching = SimulatedTeaching {
        task: &task,
        profile: "default",
        seed: args.seed,
        answers: "oracle",
        rate: None,
        realtime: false,
        output: &demo_path,
    };
    let (demo, recording, stopped) = teach_simulated(&teaching, calibration, "default", None)?;
    let (summary, learned) = learn_and_save(
        &demo,
        &recording,
        stopped,
        Some(&task),
        &calibration,
        &spec_path,
    )?;
    println!(
        "1. teach: the simulated teacher demonstrates `{}`, an oracle answers",
        task.name
    );
    print_recorded(&summary);
    println!("2. learn: AKL learns the spec from the recording");
    print_learned(&summary);
    let spec = learned.map_err(|e| {
        CliError::input(format!(
            "{}: recorded, but no spec could be learned: {e}",
            recording.display()
        ))
    })?;
    print!("{}", keyframe_table(&spec).render());
    if let Some(truth) = &task.truth {
        let s = score(&spec, truth, &Tolerance::default());
        if s.success {
            println!("  the learned spec equals the task's ground truth");
        } else {
            println!(
                "  the learned spec differs from the task's ground truth: {}",
                s.differences.join("; ")
            );
        }
    }

    println!(
        "3. execute: the learned spec in {} randomized trials",
        args.trials
    );
    let executed = execute(&Execution {
        robot: &robot,
        task: &task,
        spec: &spec,
        spec_path: &spec_path,
        randomize: Some(args.trials),
        seed: args.seed,
        jobs: args.jobs,
        trace: Some(&trace_path),
        trace_trial: None,
        options: {
            let mut options = ExecOptions::default();
            options.plan.speed_scale = args.speed.speed_scale;
            options
        },
        report: Some(&report_path),
    })?;
    print_executed(&executed);
    println!("files:");
    let trace = format!(
        "trial {}'s execution (MCAP, opens in Foxglove)",
        executed.trace_trial.unwrap_or(0)
    );
    let mut files = Table::new(["  file", "what"]);
    for (path, what) in [
        (&recording, "the demonstration (MCAP, opens in Foxglove)"),
        (&spec_path, "the learned spec"),
        (&report_path, "every trial's checks"),
        (&trace_path, trace.as_str()),
    ] {
        files.row(vec![format!("  {}", path.display()), what.to_string()]);
    }
    print!("{}", files.render());
    verdict(&executed.report)
}
