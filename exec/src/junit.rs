//! JUnit XML of a batch, so CI systems (GitHub Actions, GitLab, Jenkins) show a spec's
//! trials as test results: one test suite for the spec, one test case per trial named by its
//! seed, a failed trial's root cause as the failure's message and type, every failure of the
//! trial (root first, with its detail) as its text. The failure's type is the root cause as
//! reports name it (`grasp_failed`).

use crate::report::{BatchReport, Cause, TrialOutcome};
use std::fmt::Write;

/// What the suite is called and what it adds to the batch.
#[derive(Debug, Clone, PartialEq)]
pub struct Suite<'a> {
    /// The suite's name, e.g. `spec.json on pick_place`.
    pub name: &'a str,
    /// The test cases' class name, e.g. `akl.pick_place`.
    pub class: &'a str,
    /// Properties shown with the suite (the gate's decision, the interval).
    pub properties: Vec<(String, String)>,
}

/// The JUnit XML of `report`'s trials.
pub fn junit<T: TrialOutcome>(report: &BatchReport<T>, suite: &Suite) -> String {
    let failures = report.reports.iter().filter(|t| !t.passed()).count();
    let seconds = |t: &T| {
        let (plan, sim) = t.seconds();
        plan + sim
    };
    let total: f64 = report.reports.iter().map(seconds).sum();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuites name=\"akl\" tests=\"{}\" failures=\"{failures}\" errors=\"0\" time=\"{total:.3}\">",
        report.reports.len()
    );
    let _ = writeln!(
        out,
        "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{failures}\" errors=\"0\" skipped=\"0\" time=\"{total:.3}\">",
        escape(suite.name),
        report.reports.len()
    );
    out.push_str("    <properties>\n");
    let mut properties = vec![
        ("task".to_string(), report.task.clone()),
        ("seed".to_string(), report.seed.to_string()),
        ("pass_rate".to_string(), report.pass_rate.to_string()),
        ("interrupted".to_string(), report.interrupted.to_string()),
    ];
    properties.extend(suite.properties.iter().cloned());
    for (name, value) in &properties {
        let _ = writeln!(
            out,
            "      <property name=\"{}\" value=\"{}\"/>",
            escape(name),
            escape(value)
        );
    }
    out.push_str("    </properties>\n");
    for t in &report.reports {
        let _ = write!(
            out,
            "    <testcase name=\"seed {}\" classname=\"{}\" time=\"{:.3}\"",
            t.seed(),
            escape(suite.class),
            seconds(t)
        );
        let list = t.failure_list();
        match list.first() {
            None if t.passed() => out.push_str("/>\n"),
            first => {
                let (message, kind) = first.map_or_else(
                    || ("failed".to_string(), "failed".to_string()),
                    |(cause, detail)| (format!("{cause}: {detail}"), cause_name(*cause)),
                );
                let text: Vec<String> = list
                    .iter()
                    .enumerate()
                    .map(|(k, (cause, detail))| {
                        let role = if k == 0 { "root cause" } else { "then" };
                        format!("{role}: {cause}: {detail}")
                    })
                    .collect();
                let _ = write!(
                    out,
                    ">\n      <failure message=\"{}\" type=\"{}\">trial {} (seed {})\n{}</failure>\n    </testcase>\n",
                    escape(&message),
                    escape(&kind),
                    t.index(),
                    t.seed(),
                    escape(&text.join("\n"))
                );
            }
        }
    }
    out.push_str("  </testsuite>\n</testsuites>\n");
    out
}

/// The cause as reports name it (`grasp_failed`).
fn cause_name(cause: Cause) -> String {
    serde_json::to_value(cause)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_else(|| cause.label().to_string())
}

/// `text` with XML's special characters escaped and characters XML 1.0 forbids left out.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\n' | '\t' | '\r' => out.push(c),
            c if (c as u32) < 0x20 => {}
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_characters_are_escaped() {
        assert_eq!(
            escape("a<b & \"c\" 'd'>\u{1}"),
            "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;"
        );
    }
}
