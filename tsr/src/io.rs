//! File output that never leaves a half-written file behind.

use std::fs;
use std::io::{self, Write};
use std::path::Path;

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename, so
/// readers see either the old file or the complete new one, even if the process dies midway.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(io::ErrorKind::InvalidInput, "output path has no file name")
    })?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut file = fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_the_whole_file_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("akl-io-test-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.json");
        write_atomic(&path, b"{\"a\": 1}").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"{\"a\": 1}");
        let leftovers: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
            .collect();
        assert!(leftovers.is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn fails_cleanly_when_the_directory_is_missing() {
        let path = std::env::temp_dir().join("akl-no-such-dir-xyz/out.json");
        assert!(write_atomic(&path, b"x").is_err());
    }
}

/// Widest a JSON value may print on one line before [`to_readable_json`] breaks it up.
const INLINE_WIDTH: usize = 96;

/// JSON for people: values whose compact form fits in a line (a pose, a bounds matrix) stay on
/// one line, larger objects and arrays are indented two spaces per level.
pub fn to_readable_json<T: serde::Serialize>(value: &T) -> serde_json::Result<String> {
    let value = serde_json::to_value(value)?;
    let mut out = String::new();
    write_readable(&value, 0, &mut out);
    out.push('\n');
    Ok(out)
}

fn write_readable(value: &serde_json::Value, indent: usize, out: &mut String) {
    use serde_json::Value;
    let compact = value.to_string();
    if compact.len() + indent <= INLINE_WIDTH {
        out.push_str(&spaced(&compact, value));
        return;
    }
    let pad = "  ".repeat(indent + 1);
    match value {
        Value::Object(map) => {
            out.push_str("{\n");
            for (i, (k, v)) in map.iter().enumerate() {
                out.push_str(&pad);
                out.push_str(&Value::String(k.clone()).to_string());
                out.push_str(": ");
                write_readable(v, indent + 1, out);
                out.push_str(if i + 1 < map.len() { ",\n" } else { "\n" });
            }
            out.push_str(&"  ".repeat(indent));
            out.push('}');
        }
        Value::Array(items) => {
            out.push_str("[\n");
            for (i, v) in items.iter().enumerate() {
                out.push_str(&pad);
                write_readable(v, indent + 1, out);
                out.push_str(if i + 1 < items.len() { ",\n" } else { "\n" });
            }
            out.push_str(&"  ".repeat(indent));
            out.push(']');
        }
        _ => out.push_str(&compact),
    }
}

/// Re-serializes a small value with a space after each `:` and `,` (strings untouched).
fn spaced(compact: &str, value: &serde_json::Value) -> String {
    use serde_json::Value;
    match value {
        Value::Object(map) => {
            let parts: Vec<String> = map
                .iter()
                .map(|(k, v)| {
                    format!(
                        "{}: {}",
                        Value::String(k.clone()),
                        spaced(&v.to_string(), v)
                    )
                })
                .collect();
            format!("{{{}}}", parts.join(", "))
        }
        Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(|v| spaced(&v.to_string(), v)).collect();
            format!("[{}]", parts.join(", "))
        }
        _ => compact.to_string(),
    }
}

#[cfg(test)]
mod readable_tests {
    use super::*;

    #[test]
    fn small_values_stay_on_one_line_and_parse_back() {
        let v = serde_json::json!({"name": "a, b: c", "pose": {"p": [0.1, 0.2, 0.3], "q": [0.0, 0.0, 0.0, 1.0]},
            "list": (0..40).collect::<Vec<_>>()});
        let text = to_readable_json(&v).unwrap();
        assert!(
            text.contains("\"pose\": {\"p\": [0.1, 0.2, 0.3], \"q\": [0.0, 0.0, 0.0, 1.0]}"),
            "{text}"
        );
        assert!(text.contains("\"name\": \"a, b: c\""), "{text}");
        let back: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(back, v);
    }
}
