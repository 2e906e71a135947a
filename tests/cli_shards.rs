//! End-to-end tests of sharded runs through the binary: shards of a run merged with `akl report
//! merge` equal the single run trial by trial (whatever `--jobs` each used), mismatched,
//! missing, duplicate and interrupted parts are refused with exit 2 naming the part, an
//! interrupted part is finished with `--resume`, `--shard auto` reads Slurm's and Kubernetes'
//! variables, and `akl validate --from-report` judges the merged trials as `akl validate` does.

use std::path::Path;
use std::process::{Command, Output};

mod common;
use common::*;

/// The spec the tests run: the pick-and-place truth with goals drawn across its regions and
/// a large perception error, so that some trials fail and the totals have something to add.
const SPEC: &str = "tasks/pick_place.truth.json";
const TASK: &str = "pick_place";
const NOISE: &str = "12,6";

/// `akl args` with the scheduler's variables set to `env` (and every other one unset).
fn akl_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_akl"));
    c.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    for var in [
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_COUNT",
        "SLURM_ARRAY_TASK_MIN",
        "SLURM_ARRAY_TASK_STEP",
        "JOB_COMPLETION_INDEX",
    ] {
        c.env_remove(var);
    }
    c.envs(env.iter().copied());
    c.output().expect("the akl binary runs")
}

/// Runs `trials` trials from seed `seed` (shard `shard` if given) with `jobs` threads,
/// writing the report to `report`; checks it exited 0 or 1 (trials may fail).
fn execute(trials: usize, seed: u64, shard: Option<&str>, jobs: &str, report: &Path) -> Output {
    let trials = trials.to_string();
    let seed = seed.to_string();
    let mut args = vec![
        "execute",
        SPEC,
        "--task",
        TASK,
        "--randomize",
        &trials,
        "--seed",
        &seed,
        "--goals",
        "sampled",
        "--pose-noise",
        NOISE,
        "--jobs",
        jobs,
        "--report",
        report.to_str().unwrap(),
    ];
    if let Some(s) = shard {
        args.extend(["--shard", s]);
    }
    let o = akl_env(&args, &[]);
    assert!(
        matches!(o.status.code(), Some(0 | 1)),
        "{}\n{}",
        stdout(&o),
        stderr(&o)
    );
    o
}

fn read(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A report without what depends on the machine or on how it was split (times, threads, the
/// list of merged parts).
fn comparable(mut report: serde_json::Value) -> serde_json::Value {
    let top = report.as_object_mut().unwrap();
    for key in [
        "seconds_per_trial",
        "plan_seconds_per_trial",
        "sim_seconds_per_trial",
        "wall_seconds",
        "jobs",
        "merged",
    ] {
        top.remove(key);
    }
    for trial in top["reports"].as_array_mut().unwrap() {
        let trial = trial.as_object_mut().unwrap();
        trial.remove("plan_seconds").unwrap();
        trial.remove("sim_seconds").unwrap();
    }
    report
}

fn merge(parts: &[&Path], output: &Path) -> Output {
    let mut args = vec!["report", "merge"];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.extend(["-o", output.to_str().unwrap()]);
    akl_env(&args, &[])
}

#[test]
fn three_shards_merged_equal_the_single_run_trial_by_trial() {
    let dir = scratch("shards-120");
    let single = dir.join("single.json");
    execute(120, 3000, None, "2", &single);
    let parts: Vec<_> = (0..3).map(|i| dir.join(format!("part{i}.json"))).collect();
    for (i, part) in parts.iter().enumerate() {
        let o = execute(120, 3000, Some(&format!("{i}/3")), "1", part);
        assert!(stdout(&o).contains(&format!("shard {i}/3: 40 randomized trials")));
        let r = read(part);
        assert_eq!(r["shard"]["index"], i);
        assert_eq!(r["trials"], 40);
        assert_eq!(r["reports"][0]["trial"], 40 * i);
        assert_eq!(r["reports"][0]["seed"], 3000 + 40 * i);
    }
    let merged = dir.join("merged.json");
    // The parts in any order.
    let o = merge(&[&parts[2], &parts[0], &parts[1]], &merged);
    assert!(o.status.success(), "{}{}", stdout(&o), stderr(&o));
    assert!(stdout(&o).contains("merged 3 part(s)"), "{}", stdout(&o));
    let (one, joined) = (read(&single), read(&merged));
    assert_eq!(joined["merged"].as_array().unwrap().len(), 3);
    let failed = one["trials"].as_u64().unwrap() - one["passed"].as_u64().unwrap();
    assert!(
        failed > 0 && one["passed"].as_u64().unwrap() > 0,
        "the test needs trials that pass and trials that fail: {}",
        one["pass_rate"]
    );
    let (one, joined) = (comparable(one), comparable(joined));
    let (a, b) = (
        one["reports"].as_array().unwrap(),
        joined["reports"].as_array().unwrap(),
    );
    assert_eq!(a.len(), 120);
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x, y, "trial {} differs", x["trial"]);
    }
    for key in [
        "trials",
        "passed",
        "pass_rate",
        "failures",
        "secondary",
        "identity",
        "settings",
    ] {
        assert_eq!(one[key], joined[key], "{key}");
    }
    assert_eq!(one, joined);

    // The gate over the merged trials decides as `akl validate` does on the same seeds.
    let judged = akl_env(
        &[
            "validate",
            SPEC,
            "--task",
            TASK,
            "--pose-noise",
            NOISE,
            "--from-report",
            merged.to_str().unwrap(),
            "--json",
        ],
        &[],
    );
    let run = akl_env(
        &[
            "validate",
            SPEC,
            "--task",
            TASK,
            "--pose-noise",
            NOISE,
            "--seed",
            "3000",
            "--max-trials",
            "120",
            "--json",
        ],
        &[],
    );
    assert_eq!(
        judged.status.code(),
        run.status.code(),
        "{}",
        stderr(&judged)
    );
    let (judged, run) = (json(&judged), json(&run));
    assert_eq!(judged["decision"], run["spec"]["decision"]);
    assert_eq!(judged["trials_read"], run["spec"]["outcome"]["run"]);
    assert_eq!(judged["pass_rate"], run["spec"]["outcome"]["pass_rate"]);
    assert_eq!(
        judged["failed_seeds"],
        run["spec"]["outcome"]["failed_seeds"]
    );
    // Trials run with other settings than this validate's are refused.
    let other = akl_env(
        &[
            "validate",
            "tasks/pick_place.truth.json",
            "--task",
            TASK,
            "--from-report",
            merged.to_str().unwrap(),
        ],
        &[],
    );
    assert_refused(&other, &["as validation runs them"]);
}

#[test]
fn parts_of_different_runs_missing_duplicate_or_interrupted_are_refused_naming_the_part() {
    let dir = scratch("shards-bad");
    let p = |name: &str| dir.join(name);
    execute(6, 50, Some("0/2"), "2", &p("a0.json"));
    execute(6, 50, Some("1/2"), "2", &p("a1.json"));
    let refused = |parts: &[&Path], says: &[&str]| {
        let out = p("out.json");
        let o = merge(parts, &out);
        assert_refused(&o, says);
        assert!(!out.exists(), "nothing is written");
    };
    // Another seed, another noise, another spec: each part named with what differs.
    execute(6, 51, Some("1/2"), "2", &p("seed.json"));
    refused(
        &[&p("a0.json"), &p("seed.json")],
        &["seed.json", "the seed"],
    );
    let o = akl_env(
        &[
            "execute",
            SPEC,
            "--task",
            TASK,
            "--randomize",
            "6",
            "--seed",
            "50",
            "--goals",
            "sampled",
            "--shard",
            "1/2",
            "--report",
            p("noise.json").to_str().unwrap(),
        ],
        &[],
    );
    assert!(matches!(o.status.code(), Some(0 | 1)));
    refused(
        &[&p("a0.json"), &p("noise.json")],
        &["noise.json", "execution settings"],
    );
    let o = akl_env(
        &[
            "execute",
            "tasks/inspection.truth.json",
            "--task",
            "inspection",
            "--randomize",
            "6",
            "--seed",
            "50",
            "--shard",
            "1/2",
            "--report",
            p("spec.json").to_str().unwrap(),
        ],
        &[],
    );
    assert!(matches!(o.status.code(), Some(0 | 1)));
    refused(
        &[&p("a0.json"), &p("spec.json")],
        &["spec.json", "the spec"],
    );
    refused(&[&p("a0.json")], &["shard(s) 1 of 2 missing"]);
    refused(
        &[&p("a0.json"), &p("a1.json"), &p("a0.json")],
        &["shard 0/2 is given twice"],
    );
    std::fs::write(p("junk.json"), "{\"akl_report\": 1").unwrap();
    refused(&[&p("a0.json"), &p("junk.json")], &["junk.json"]);

    // An interrupted part is refused until --resume finishes it; then it equals the part.
    let mut cut = read(&p("a1.json"));
    let whole = cut.clone();
    cut["reports"].as_array_mut().unwrap().truncate(1);
    cut["interrupted"] = true.into();
    cut["trials"] = 1.into();
    std::fs::write(p("cut.json"), serde_json::to_string(&cut).unwrap()).unwrap();
    refused(&[&p("a0.json"), &p("cut.json")], &["cut.json", "--resume"]);
    let resume = |shard: &str| {
        akl_env(
            &[
                "execute",
                SPEC,
                "--task",
                TASK,
                "--randomize",
                "6",
                "--seed",
                "50",
                "--goals",
                "sampled",
                "--pose-noise",
                NOISE,
                "--shard",
                shard,
                "--resume",
                p("cut.json").to_str().unwrap(),
            ],
            &[],
        )
    };
    let o = resume("0/2");
    assert_refused(&o, &["the shard"]);
    let o = resume("1/2");
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let resumed = read(&p("cut.json"));
    assert_eq!(resumed["interrupted"], false);
    assert_eq!(comparable(resumed), comparable(whole));
    let o = merge(&[&p("a0.json"), &p("cut.json")], &p("out.json"));
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn shard_auto_reads_slurm_or_kubernetes_and_says_when_neither_is_set() {
    let dir = scratch("shards-auto");
    let report = dir.join("r.json");
    let run = |shard: &str, env: &[(&str, &str)]| {
        akl_env(
            &[
                "execute",
                "tasks/inspection.truth.json",
                "--task",
                "inspection",
                "--randomize",
                "4",
                "--shard",
                shard,
                "--report",
                report.to_str().unwrap(),
            ],
            env,
        )
    };
    let o = run("auto", &[]);
    assert_refused(&o, &["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"]);
    let o = run(
        "auto",
        &[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let r = read(&report);
    assert_eq!(
        (r["shard"]["index"].as_u64(), r["shard"]["count"].as_u64()),
        (Some(1), Some(2))
    );
    let trials: Vec<u64> = r["reports"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["trial"].as_u64().unwrap())
        .collect();
    assert_eq!(trials, [2, 3]);
    let o = run("auto", &[("JOB_COMPLETION_INDEX", "0")]);
    assert_refused(&o, &["auto/N"]);
    let o = run("auto/4", &[("JOB_COMPLETION_INDEX", "3")]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(read(&report)["reports"][0]["trial"], 3);
    let o = run("5/4", &[]);
    assert_eq!(o.status.code(), Some(2));
    let o = run("0/5", &[]);
    assert_refused(&o, &["holds no trial"]);
}
