//! End-to-end tests of `akl validate`, `akl relax` and `akl compare` through the binary.

mod common;
use common::*;
use std::path::{Path, PathBuf};

/// The pick_place truth with a world-grounded via-point 10 cm above the first carry, written
/// to `dir`.
fn via_point_spec(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/pick_place.truth.json"),
    )
    .unwrap();
    let mut spec: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut extra = spec["keyframes"][0].clone();
    extra["reference"] = "world".into();
    extra["kind"] = "constraint".into();
    extra["tsr"]["t0_w"] = serde_json::json!({"p": [0, 0, 0], "q": [0, 0, 0, 1]});
    extra["tsr"]["tw_e"] = serde_json::json!({"p": [0.32, 0.0, 0.33], "q": [1, 0, 0, 0]});
    spec["keyframes"].as_array_mut().unwrap().insert(1, extra);
    let path = dir.join("via.json");
    std::fs::write(&path, serde_json::to_string_pretty(&spec).unwrap()).unwrap();
    path
}

#[test]
fn a_minimal_truth_passes_the_gate_and_a_via_point_is_named() {
    let o = akl(&[
        "validate",
        "tasks/pick_place.truth.json",
        "--task",
        "pick_place",
        "--randomize",
        "4",
    ]);
    assert!(o.status.success(), "{}{}", stdout(&o), stderr(&o));
    assert!(
        stdout(&o).contains("verdict: passes, minimal"),
        "{}",
        stdout(&o)
    );

    let dir = scratch("validate-via");
    let via = via_point_spec(&dir);
    let o = akl(&[
        "validate",
        via.to_str().unwrap(),
        "--task",
        "pick_place",
        "--randomize",
        "4",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["verdict"], "not_minimal", "{v}");
    assert_eq!(v["outcome"]["passed"], 4, "{v}");
    let superfluous: Vec<&serde_json::Value> = v["removals"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["essential"] == false)
        .collect();
    assert_eq!(superfluous.len(), 1, "{v}");
    assert_eq!(superfluous[0]["remove"], "keyframe");
    assert_eq!(superfluous[0]["keyframe"], 1);
}

#[test]
fn a_wrong_no_is_contradicted_by_the_simulation() {
    let dir = scratch("validate-demo");
    let o = akl_in(
        &dir,
        &[
            "teach",
            "--task",
            "inspection",
            "--answers",
            "no",
            "-o",
            "no.mcap",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = akl_in(
        &dir,
        &[
            "validate",
            "no.spec.json",
            "--task",
            "inspection",
            "--demo",
            "no.mcap",
            "--randomize",
            "4",
            "--json",
        ],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["verdict"], "fails", "{v}");
    let answers = &v["answers"];
    assert_eq!(answers["spec_is_learned_from_demo"], true, "{answers}");
    let checks = answers["checks"].as_array().unwrap();
    assert_eq!(checks.len(), 1, "{answers}");
    assert_eq!(checks[0]["answer"], "no");
    assert_eq!(checks[0]["verdict"], "contradicted", "{answers}");
    assert_eq!(checks[0]["lines_when_flipped"], 1);
}

#[test]
fn relax_writes_a_verified_wider_spec() {
    let dir = scratch("relax");
    let out = dir.join("relaxed.json");
    let o = akl(&[
        "relax",
        "tasks/pick_place.truth.json",
        "--task",
        "pick_place",
        "--trials",
        "3",
        "--depth",
        "1",
        "--verify",
        "8",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json(&o);
    assert!(v["bits_after"].as_f64().unwrap() > v["bits_before"].as_f64().unwrap());
    let last = v["verifications"].as_array().unwrap().last().unwrap();
    assert_eq!(last["outcome"]["passed"], 8, "{last}");
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(written["method"], "truth+relaxed");
    assert_eq!(written, v["relaxed"]);

    // A bad count exits 2 and writes nothing.
    let o = akl(&[
        "relax",
        "tasks/pick_place.truth.json",
        "--task",
        "pick_place",
        "--verify",
        "0",
        "-o",
        dir.join("other.json").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--verify"), "{}", stderr(&o));
    assert!(!dir.join("other.json").exists());
}

#[test]
fn compare_prints_a_row_per_spec() {
    let dir = scratch("compare");
    let via = via_point_spec(&dir);
    let o = akl(&[
        "compare",
        "tasks/pick_place.truth.json",
        via.to_str().unwrap(),
        "--task",
        "pick_place",
        "--randomize",
        "3",
        "--scenes",
        "2",
        "--budget",
        "0",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json(&o);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0]["keyframes"], 4);
    assert_eq!(rows[1]["keyframes"], 5);
    assert!(rows[0]["bits"].as_f64().unwrap() > rows[1]["bits"].as_f64().unwrap());
    assert_eq!(rows[0]["verdict"], "passes");
    assert_eq!(rows[1]["verdict"], "not_minimal");
    assert_eq!(rows[0]["plan_success"], 1.0);

    let o = akl(&[
        "compare",
        "tasks/pick_place.truth.json",
        via.to_str().unwrap(),
        "--task",
        "pick_place",
        "--randomize",
        "2",
        "--scenes",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = stdout(&o);
    assert!(
        table.contains("bits") && table.contains("validation"),
        "{table}"
    );
    assert!(table.contains("not essential: keyframe 1"), "{table}");
}

#[test]
fn bad_input_exits_2_naming_what_is_wrong() {
    let o = akl(&["validate", "no/such/spec.json", "--task", "inspection"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no/such/spec.json"), "{}", stderr(&o));

    let o = akl(&[
        "validate",
        "tasks/assembly.truth.json",
        "--task",
        "inspection",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("assembly.truth.json"), "{}", stderr(&o));

    let o = akl(&[
        "validate",
        "tasks/pick_place.truth.json",
        "--task",
        "pick_place",
        "--randomize",
        "0",
    ]);
    assert_eq!(o.status.code(), Some(2));

    let o = akl(&[
        "compare",
        "tasks/pick_place.truth.json",
        "tasks/inspection.truth.json",
        "--task",
        "pick_place",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("inspection.truth.json"),
        "{}",
        stderr(&o)
    );

    let dir = scratch("validate-bad-demo");
    let demo = dir.join("demo.jsonl");
    std::fs::write(&demo, "not json\n").unwrap();
    let o = akl(&[
        "validate",
        "tasks/inspection.truth.json",
        "--task",
        "inspection",
        "--demo",
        demo.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("demo.jsonl"), "{}", stderr(&o));
}

/// Teaches pick_place with the straight-moving teacher answering `answers` in `dir`, then
/// validates the learned spec against its demonstration; returns the JSON and the exit code.
fn validate_answers(dir: &Path, answers: &str) -> (serde_json::Value, Option<i32>) {
    let o = akl_in(
        dir,
        &[
            "teach",
            "--task",
            "pick_place",
            "--profile",
            "straight",
            "--answers",
            answers,
            "-o",
            "demo.mcap",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = akl_in(
        dir,
        &[
            "validate",
            "demo.spec.json",
            "--task",
            "pick_place",
            "--demo",
            "demo.mcap",
            "--randomize",
            "4",
            "--json",
        ],
    );
    (json(&o), o.status.code())
}

#[test]
fn a_wrong_yes_is_contradicted_and_a_failing_spec_confirms_nothing() {
    let dir = scratch("validate-yes");
    // The straight-moving teacher makes five unintended lines; a "yes" to the fourth alone.
    let (v, code) = validate_answers(&dir, "no,no,no,yes,no");
    assert_eq!(code, Some(1));
    assert_eq!(v["verdict"], "not_minimal", "{v}");
    let checks = v["answers"]["checks"].as_array().unwrap();
    let verdicts: Vec<&str> = checks
        .iter()
        .map(|c| c["verdict"].as_str().unwrap())
        .collect();
    assert_eq!(
        verdicts,
        [
            "confirmed",
            "confirmed",
            "confirmed",
            "contradicted",
            "confirmed"
        ],
        "{v}"
    );

    // A "yes" to the first, a line into the first grasp: the spec passes no trial, so no
    // trial can confirm any answer.
    let (v, code) = validate_answers(&dir, "yes,no,no,no,no");
    assert_eq!(code, Some(1));
    assert_eq!(v["outcome"]["passed"], 0, "{v}");
    for c in v["answers"]["checks"].as_array().unwrap() {
        assert_ne!(c["verdict"], "confirmed", "{c}");
    }
}
