//! End-to-end tests of `--junit` through the binary: the XML of `akl execute` and `akl
//! validate` parses, has one test case per trial named by its seed and one failure per failed
//! trial carrying its root cause and detail; and, standard error not being a terminal here, a
//! run reports its progress in one line per tenth.

use std::path::Path;

mod common;
use common::*;

/// A test case: its name, and its failure's message and type if it failed.
type Case = (String, Option<(String, String)>);

/// The JUnit file at `path`, parsed, and its test cases.
fn cases(path: &Path) -> (roxmltree::Document<'static>, Vec<Case>) {
    let text: &'static str = Box::leak(std::fs::read_to_string(path).unwrap().into_boxed_str());
    let doc = roxmltree::Document::parse(text).unwrap_or_else(|e| panic!("{e}: {text}"));
    let cases = doc
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .map(|n| {
            let failure = n.children().find(|c| c.has_tag_name("failure")).map(|f| {
                (
                    f.attribute("message").unwrap().to_string(),
                    f.attribute("type").unwrap().to_string(),
                )
            });
            (n.attribute("name").unwrap().to_string(), failure)
        })
        .collect();
    (doc, cases)
}

#[test]
fn execute_junit_has_a_test_case_per_trial_and_a_failure_per_failed_trial() {
    let dir = scratch("junit-execute");
    let (xml, report) = (dir.join("trials.xml"), dir.join("report.json"));
    let o = akl(&[
        "execute",
        "tasks/pick_place.truth.json",
        "--task",
        "pick_place",
        "--randomize",
        "20",
        "--seed",
        "3000",
        "--goals",
        "sampled",
        "--pose-noise",
        "12,6",
        "--jobs",
        "1",
        "--junit",
        xml.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let (doc, cases) = cases(&xml);
    assert_eq!(cases.len(), 20);
    let failed: Vec<&serde_json::Value> = r["reports"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|t| t["passed"] == false)
        .collect();
    assert!(!failed.is_empty(), "the test needs a failed trial");
    assert_eq!(
        cases.iter().filter(|(_, f)| f.is_some()).count(),
        failed.len()
    );
    let suite = doc
        .descendants()
        .find(|n| n.has_tag_name("testsuite"))
        .unwrap();
    assert_eq!(suite.attribute("tests"), Some("20"));
    assert_eq!(
        suite.attribute("failures"),
        Some(failed.len().to_string().as_str())
    );
    for (k, (name, _)) in cases.iter().enumerate() {
        assert_eq!(name, &format!("seed {}", 3000 + k));
    }
    for t in failed {
        let name = format!("seed {}", t["seed"]);
        let (message, kind) = cases
            .iter()
            .find(|(n, _)| *n == name)
            .and_then(|(_, f)| f.clone())
            .unwrap_or_else(|| panic!("{name} is not a failure"));
        let root = &t["failures"][0];
        assert_eq!(root["root"], true);
        assert_eq!(kind, root["cause"].as_str().unwrap());
        assert!(
            message.ends_with(root["detail"].as_str().unwrap()),
            "{message} / {root}"
        );
    }
    // Standard error is not a terminal: one progress line per tenth.
    let lines: Vec<&str> = o
        .stderr
        .split(|&b| b == b'\n')
        .map(|l| std::str::from_utf8(l).unwrap())
        .filter(|l| l.contains("trials ("))
        .collect();
    assert_eq!(lines.len(), 10, "{}", stderr(&o));
    assert!(lines[9].contains("20/20 trials (100 %)"), "{}", lines[9]);
}

#[test]
fn validate_junit_holds_the_trials_the_gate_read_and_its_decision() {
    let dir = scratch("junit-validate");
    let xml = dir.join("gate.xml");
    let mut wrong: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/pick_place.truth.json"),
        )
        .unwrap(),
    )
    .unwrap();
    // The first block is never put down: every trial fails, and the gate fails at trial 1.
    wrong["keyframes"].as_array_mut().unwrap().truncate(1);
    let spec = dir.join("wrong.json");
    std::fs::write(&spec, serde_json::to_string(&wrong).unwrap()).unwrap();
    let o = akl(&[
        "validate",
        spec.to_str().unwrap(),
        "--task",
        "pick_place",
        "--junit",
        xml.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let (doc, cases) = cases(&xml);
    assert_eq!(cases.len(), 1);
    assert_eq!(cases[0].0, "seed 0");
    assert!(cases[0].1.is_some());
    let decision = doc
        .descendants()
        .find(|n| n.has_tag_name("property") && n.attribute("name") == Some("decision"))
        .unwrap();
    assert_eq!(decision.attribute("value"), Some("fails"));
}
