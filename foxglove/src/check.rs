//! Checking messages against the JSON schemas written beside them (the `check` feature).
//!
//! The checker knows the keywords [`crate::schema`]'s builders write (`type`, `properties`,
//! `required`, `additionalProperties: false`, `items`, `enum`, and the annotations `title` and
//! `description`); a schema with any other keyword is refused rather than half checked.

use std::collections::BTreeMap;

use serde_json::Value;

/// Where and how a message breaks its schema.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{at}: {problem}")]
pub struct Violation {
    /// Where: the topic and message number, then the path to the field (`/tf #3 .transforms[0]`).
    pub at: String,
    /// What is wrong.
    pub problem: String,
}

fn violation(at: &str, problem: String) -> Violation {
    Violation {
        at: at.to_string(),
        problem,
    }
}

/// Checks `value` against `schema`; `at` names where `value` is, for the report.
pub(crate) fn check(schema: &Value, value: &Value, at: &str) -> Result<(), Violation> {
    let Value::Object(keywords) = schema else {
        return Err(violation(
            at,
            format!("the schema {schema} is not an object"),
        ));
    };
    for keyword in keywords.keys() {
        if !matches!(
            keyword.as_str(),
            "type"
                | "properties"
                | "required"
                | "additionalProperties"
                | "items"
                | "enum"
                | "title"
                | "description"
        ) {
            return Err(violation(
                at,
                format!("the schema keyword `{keyword}` is not supported"),
            ));
        }
    }
    if let Some(kind) = keywords.get("type") {
        let fits = match kind.as_str() {
            Some("object") => value.is_object(),
            Some("array") => value.is_array(),
            Some("string") => value.is_string(),
            Some("boolean") => value.is_boolean(),
            Some("number") => value.is_number(),
            Some("integer") => value.is_i64() || value.is_u64(),
            _ => return Err(violation(at, format!("unknown type {kind}"))),
        };
        if !fits {
            return Err(violation(at, format!("{value} is not of type {kind}")));
        }
    }
    if let Some(Value::Array(allowed)) = keywords.get("enum") {
        if !allowed.contains(value) {
            return Err(violation(at, format!("{value} is not one of {allowed:?}")));
        }
    }
    if let Value::Object(fields) = value {
        let properties = keywords.get("properties").and_then(Value::as_object);
        for name in keywords
            .get("required")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(Value::as_str)
        {
            if !fields.contains_key(name) {
                return Err(violation(at, format!("the field `{name}` is missing")));
            }
        }
        let closed = keywords.get("additionalProperties") == Some(&Value::Bool(false));
        for (name, field) in fields {
            match properties.and_then(|p| p.get(name)) {
                Some(schema) => check(schema, field, &format!("{at}.{name}"))?,
                None if closed => {
                    return Err(violation(
                        at,
                        format!("the field `{name}` is not in the schema"),
                    ))
                }
                None => {}
            }
        }
    }
    if let (Value::Array(items), Some(schema)) = (value, keywords.get("items")) {
        for (i, item) in items.iter().enumerate() {
            check(schema, item, &format!("{at}[{i}]"))?;
        }
    }
    Ok(())
}

/// Checks every message of the MCAP file `bytes` against its channel's JSON schema; returns
/// the number of messages checked per topic. A channel must be JSON with a `jsonschema` schema.
pub fn check_mcap(bytes: &[u8]) -> Result<BTreeMap<String, usize>, Violation> {
    let stream = mcap::MessageStream::new(bytes).map_err(|e| violation("file", e.to_string()))?;
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for message in stream {
        let message = message.map_err(|e| violation("file", e.to_string()))?;
        let channel = &message.channel;
        let count = counts.entry(channel.topic.clone()).or_default();
        let at = format!("{} #{count}", channel.topic);
        *count += 1;
        if channel.message_encoding != "json" {
            return Err(violation(
                &at,
                format!("encoded {}, not json", channel.message_encoding),
            ));
        }
        let schema = match &channel.schema {
            Some(s) if s.encoding == "jsonschema" => s,
            _ => return Err(violation(&at, "no JSON schema".into())),
        };
        let schema: Value = serde_json::from_slice(&schema.data)
            .map_err(|e| violation(&at, format!("the schema is not JSON: {e}")))?;
        let value: Value = serde_json::from_slice(&message.data)
            .map_err(|e| violation(&at, format!("not JSON: {e}")))?;
        check(&schema, &value, &at)?;
    }
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{Color, Line, LineType, Log, LogLevel, Pose, SceneEntity, SceneUpdate};
    use crate::schema::{Message, Schema};
    use serde_json::json;

    fn log() -> Value {
        serde_json::to_value(Log::new(1.0, LogLevel::Info, "akl.test", "hello".into())).unwrap()
    }

    #[test]
    fn a_log_fits_its_schema() {
        check(&Log::schema(), &log(), "log").unwrap();
    }

    #[test]
    fn a_misnamed_missing_or_mistyped_field_breaks_the_schema() {
        let schema = Log::titled_schema();
        let mut misnamed = log();
        let level = misnamed.as_object_mut().unwrap().remove("level").unwrap();
        misnamed["severity"] = level;
        let e = check(&schema, &misnamed, "log").unwrap_err();
        assert!(e.problem.contains("`level` is missing"), "{e}");
        let mut extra = log();
        extra["severity"] = json!(2);
        let e = check(&schema, &extra, "log").unwrap_err();
        assert!(e.problem.contains("`severity` is not in the schema"), "{e}");
        let mut wrong = log();
        wrong["timestamp"]["nsec"] = json!(0.5);
        let e = check(&schema, &wrong, "log").unwrap_err();
        assert_eq!(e.at, "log.timestamp.nsec");
        let mut level = log();
        level["level"] = json!(7);
        assert!(check(&schema, &level, "log").is_err());
    }

    #[test]
    fn array_items_are_checked_one_by_one() {
        let mut entity = SceneEntity::new(0.0, "world", "e");
        entity.lines.push(Line {
            kind: LineType::Strip,
            pose: Pose::from(&akl_tsr::Pose::identity()),
            thickness: 0.1,
            scale_invariant: false,
            points: Vec::new(),
            color: Color::from([1.0, 0.0, 0.0, 1.0]),
            colors: Vec::new(),
            indices: Vec::new(),
        });
        let mut value = serde_json::to_value(SceneUpdate::new(vec![entity])).unwrap();
        check(&SceneUpdate::schema(), &value, "u").unwrap();
        value["entities"][0]["lines"][0]["points"] = json!([{"x": 1.0, "y": 2.0}]);
        let e = check(&SceneUpdate::schema(), &value, "u").unwrap_err();
        assert_eq!(e.at, "u.entities[0].lines[0].points[0]");
        assert!(e.problem.contains("`z` is missing"), "{e}");
    }

    #[test]
    fn an_unknown_keyword_is_refused_not_ignored() {
        let schema = json!({"type": "string", "maxLength": 2});
        assert!(check(&schema, &json!("long"), "s").is_err());
    }
}
