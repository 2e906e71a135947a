//! End-to-end tests of `akl eval`: a small simulated study, its per-trial CSV checked against
//! the tables it printed, the JSON and figures it wrote, reproducibility, execution of the
//! learned specs, and bad input.

use std::collections::BTreeMap;

mod common;
use common::*;

/// (task, method) → (successes, trials), counted from the CSV rows.
fn tally(csv: &str) -> BTreeMap<(String, String), (usize, usize)> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (task, method, success) = (col("task"), col("method"), col("success"));
    let mut out = BTreeMap::new();
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), header.len(), "{line}");
        for t in [cells[task], "overall"] {
            let e = out
                .entry((t.to_string(), cells[method].to_string()))
                .or_insert((0, 0));
            e.0 += usize::from(cells[success] == "true");
            e.1 += 1;
        }
    }
    out
}

#[test]
fn a_small_study_writes_records_that_agree_with_its_tables() {
    let dir = scratch("eval");
    let o = akl_in(
        &dir,
        &[
            "eval",
            "--participants",
            "3",
            "--seed",
            "4",
            "--out",
            "out",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let report = json(&o);
    let csv = std::fs::read_to_string(dir.join("out/trials.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 27);
    let counted = tally(&csv);
    let rows = report["summary"]["success"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    for row in rows {
        let task = row["task"].as_str().unwrap();
        for method in ["kd", "macl", "akl"] {
            let (successes, trials) = counted[&(task.to_string(), method.to_string())];
            let rate = &row[method];
            assert_eq!(rate["successes"], successes, "{task} {method}");
            assert_eq!(rate["trials"], trials, "{task} {method}");
            let percent = 100.0 * successes as f64 / trials as f64;
            assert!((rate["percent"].as_f64().unwrap() - percent).abs() < 1e-9);
        }
    }
    // The printed table shows the same counts (same seed, same study).
    let o = akl_in(&dir, &["eval", "--participants", "3", "--seed", "4"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    let overall = text
        .lines()
        .find(|l| l.starts_with("overall"))
        .unwrap_or_else(|| panic!("{text}"));
    for method in ["kd", "macl", "akl"] {
        let (s, n) = counted[&("overall".to_string(), method.to_string())];
        assert!(
            overall.contains(&format!("({s}/{n})")),
            "{method}: {overall}"
        );
    }
    assert!(
        text.contains("Table 4.2") && text.contains("runtime"),
        "{text}"
    );
    // Counterbalanced: with three participants each method is taught first once.
    let trials = report["trials"].as_array().unwrap();
    for method in ["kd", "macl", "akl"] {
        let first = trials
            .iter()
            .filter(|t| t["method"] == method && t["position"] == 1)
            .count();
        assert_eq!(first, 3, "{method}");
    }
    // The JSON record holds the population, participants and every spec; the figures exist.
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/trials.json")).unwrap())
            .unwrap();
    assert_eq!(record["participants"].as_array().unwrap().len(), 3);
    assert!(record["population"]["experienced_share"].is_number());
    let with_spec = record["trials"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|t| t["spec"]["keyframes"].is_array())
        .count();
    assert_eq!(with_spec, 27);
    for figure in ["keyframes", "poses", "constraint_length", "runtime"] {
        let svg = std::fs::read_to_string(dir.join(format!("out/{figure}.svg"))).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("AKL"), "{figure}");
    }
}

#[test]
fn execute_runs_every_learned_spec_in_simulation() {
    let dir = scratch("eval-execute");
    let o = akl_in(
        &dir,
        &["eval", "--participants", "1", "--execute", "1", "--json"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let report = json(&o);
    for t in report["trials"].as_array().unwrap() {
        let rate = t["pass_rate"].as_f64();
        assert!(
            rate.is_some_and(|r| r == 0.0 || r == 1.0) || t["spec"].is_null(),
            "{t}"
        );
        if t["method"] == "akl" && t["success"] == true {
            assert_eq!(rate, Some(1.0), "a correct spec fails to run: {t}");
        }
    }
    let rows = report["summary"]["pass_rates"].as_array().unwrap();
    let overall = rows.last().unwrap();
    assert_eq!(overall["task"], "overall");
    // Every method's executions pooled, with the interval: AKL's three specs ran once each.
    let akl = &overall["pass_rate"][2];
    assert_eq!(akl["trials"], 3, "{overall}");
    assert!(akl["lower"].as_f64().unwrap() <= akl["upper"].as_f64().unwrap());
    let text = stdout(&akl_in(
        &dir,
        &["eval", "--participants", "1", "--execute", "1"],
    ));
    assert!(text.contains("95 % CI"), "{text}");
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let dir = scratch("eval-bad");
    std::fs::write(dir.join("file"), "x").unwrap();
    for args in [
        vec!["eval", "--participants", "0"],
        vec!["eval", "--participants", "1", "--execute", "0"],
        vec!["eval", "--participants", "1", "--out", "file"],
    ] {
        let o = akl_in(&dir, &args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).is_empty());
    }
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(left.len(), 1);
}
