//! End-to-end test of a sharded simulated study: `akl eval --shard I/N` runs a block of the
//! participants, `akl eval --merge` joins the shards' trials.json into the whole study's, and
//! shards of another study or a missing shard are refused with exit 2 naming the part.

mod common;
use common::*;

/// A study's trials.json without the learning runtimes (the only thing that differs between
/// runs).
fn without_runtimes(mut record: serde_json::Value) -> serde_json::Value {
    for t in record["trials"].as_array_mut().unwrap() {
        t.as_object_mut().unwrap().remove("runtime_s").unwrap();
    }
    record.as_object_mut().unwrap().remove("summary").unwrap();
    record
}

/// Whether two JSON values are equal but for floating-point numbers within 1e-12: a learned
/// spec read back from trials.json has its quaternions normalized again, which may change their
/// last digit.
fn same(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(x), Some(y)) if x.fract() != 0.0 || y.fract() != 0.0 => (x - y).abs() <= 1e-12,
            _ => x == y,
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same(x, y))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

fn read(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn shards_of_a_study_merged_equal_the_whole_study() {
    let dir = scratch("eval-shards");
    let run = |args: &[&str]| {
        let o = akl_in(&dir, args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        o
    };
    run(&[
        "eval",
        "--participants",
        "3",
        "--seed",
        "4",
        "--out",
        "whole",
    ]);
    run(&[
        "eval",
        "--participants",
        "3",
        "--seed",
        "4",
        "--shard",
        "0/2",
        "--out",
        "a",
    ]);
    run(&[
        "eval",
        "--participants",
        "3",
        "--seed",
        "4",
        "--shard",
        "1/2",
        "--out",
        "b",
    ]);
    let a = read(&dir.join("a/trials.json"));
    assert_eq!(a["participants"].as_array().unwrap().len(), 1);
    assert_eq!(a["drawn"], 3);
    let o = run(&[
        "eval",
        "--merge",
        "b/trials.json",
        "a/trials.json",
        "--out",
        "merged",
    ]);
    assert!(stdout(&o).contains("3 participants"), "{}", stdout(&o));
    let whole = without_runtimes(read(&dir.join("whole/trials.json")));
    let merged = without_runtimes(read(&dir.join("merged/trials.json")));
    assert_eq!(whole["trials"].as_array().unwrap().len(), 27);
    let (a, b) = (
        whole["trials"].as_array().unwrap(),
        merged["trials"].as_array().unwrap(),
    );
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!(same(x, y), "participant {} differs", x["participant"]);
    }
    assert!(same(&whole, &merged));
    // The tables but the runtimes agree too.
    let table = |name: &str| {
        let r = read(&dir.join(name).join("trials.json"));
        (
            r["summary"]["success"].clone(),
            r["summary"]["constraint_errors"].clone(),
        )
    };
    assert_eq!(table("whole"), table("merged"));

    run(&[
        "eval",
        "--participants",
        "3",
        "--seed",
        "5",
        "--shard",
        "1/2",
        "--out",
        "c",
    ]);
    for (parts, says) in [
        (
            vec!["a/trials.json", "c/trials.json"],
            "c/trials.json: not a shard of the study",
        ),
        (
            vec!["a/trials.json"],
            "participants 2 to 3 (of 3) are in no part given",
        ),
        (
            vec!["a/trials.json", "whole/trials.json"],
            "whole/trials.json",
        ),
    ] {
        let mut args = vec!["eval", "--merge"];
        args.extend(parts);
        let o = akl_in(&dir, &args);
        assert_refused(&o, &[says]);
    }
}
