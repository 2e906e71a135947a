//! End-to-end tests of `akl flexibility` through the binary.

mod common;
use common::*;

#[test]
fn the_table_reports_bits_shares_and_the_planners_gains() {
    let o = akl(&[
        "flexibility",
        "tasks/inspection.truth.json",
        "--task",
        "inspection",
        "--scenes",
        "2",
        "--budget",
        "50",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("bits of freedom"), "{out}");
    assert!(
        out.contains("its share") && out.contains("line to 2"),
        "{out}"
    );
    assert!(out.contains("planned 2/2"), "{out}");
    assert!(out.contains("joint-path length"), "{out}");
}

#[test]
fn json_has_the_count_each_share_and_the_gains() {
    let o = akl(&[
        "flexibility",
        "tasks/pick_place.truth.json",
        "--task",
        "pick_place",
        "--scenes",
        "1",
        "--budget",
        "0",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json(&o);
    let bits = v["freedom"]["bits"].as_f64().unwrap();
    let unconstrained = v["freedom"]["unconstrained_bits"].as_f64().unwrap();
    assert!(bits > 0.0 && unconstrained > bits, "{v}");
    let traces = v["freedom"]["traces"].as_str().unwrap();
    assert!(traces.len() > 30 && traces.chars().all(|c| c.is_ascii_digit()));
    let shares = v["freedom"]["keyframes"].as_array().unwrap();
    assert_eq!(shares.len(), 4);
    for s in shares {
        assert!(s["share"].as_f64().unwrap() > 0.0, "{s}");
    }
    assert_eq!(v["freedom"]["lines"].as_array().unwrap().len(), 0);
    assert_eq!(v["gains"]["planned"], 1);
    assert_eq!(v["gains"]["candidates"], 1);
}

#[test]
fn a_redundant_keyframe_costs_bits_through_the_cli() {
    let dir = scratch("flexibility-redundant");
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/pick_place.truth.json"),
    )
    .unwrap();
    let mut spec: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut extra = spec["keyframes"][0].clone();
    extra["reference"] = "world".into();
    extra["kind"] = "constraint".into();
    extra["tsr"]["t0_w"]["p"] = serde_json::json!([0.45, 0.0, 0.4]);
    extra["tsr"]["tw_e"] = serde_json::json!({"p": [0, 0, 0], "q": [0, 0, 0, 1]});
    spec["keyframes"].as_array_mut().unwrap().insert(1, extra);
    let path = dir.join("redundant.json");
    std::fs::write(&path, serde_json::to_string_pretty(&spec).unwrap()).unwrap();
    let bits = |file: &str| {
        let o = akl(&[
            "flexibility",
            file,
            "--task",
            "pick_place",
            "--scenes",
            "0",
            "--json",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        json(&o)["freedom"]["bits"].as_f64().unwrap()
    };
    let truth = bits("tasks/pick_place.truth.json");
    let redundant = bits(path.to_str().unwrap());
    assert!(redundant < truth, "{redundant} >= {truth}");
}

#[test]
fn bad_input_exits_2_naming_the_file() {
    let o = akl(&["flexibility", "no/such/spec.json", "--task", "inspection"]);
    assert_refused(&o, &["no/such/spec.json"]);

    let dir = scratch("flexibility-bad");
    let broken = dir.join("broken.json");
    std::fs::write(&broken, "{\"akl_spec\": 1, \"task\": ").unwrap();
    let o = akl(&[
        "flexibility",
        broken.to_str().unwrap(),
        "--task",
        "inspection",
    ]);
    assert_refused(&o, &["broken.json"]);

    let o = akl(&[
        "flexibility",
        "tasks/assembly.truth.json",
        "--task",
        "inspection",
        "--scenes",
        "0",
    ]);
    assert_refused(&o, &["assembly.truth.json"]);
}
