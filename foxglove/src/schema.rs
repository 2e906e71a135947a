//! JSON schemas of the messages, and the builders a crate's own message types use.
//!
//! An object schema lists every field it is given as required and allows no other, so a
//! message whose field is misnamed or missing breaks its schema. Foxglove reads the schema only
//! for the field names and types; the strictness is for AKL's own checks.

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::messages::{
    Arrow, Color, Cylinder, FrameTransform, FrameTransforms, KeyValuePair, Line, Log, Model, Pose,
    PoseInFrame, Quaternion, SceneEntity, SceneEntityDeletion, SceneUpdate, Solid, Text, Time,
    TriangleList, Vector3,
};

/// A type with a JSON schema.
pub trait Schema {
    /// The JSON schema (draft 2020-12) of this type's JSON.
    fn schema() -> Value;
}

/// A message written on an MCAP channel: a type with a schema and the schema's name.
pub trait Message: Serialize + Schema {
    /// The schema's name, e.g. `foxglove.Log` (Foxglove picks its panels by it).
    const NAME: &'static str;

    /// The schema as written into a file: [`Schema::schema`] with the name as its `title`.
    fn titled_schema() -> Value {
        let mut schema = Self::schema();
        if let Value::Object(map) = &mut schema {
            map.insert("title".into(), json!(Self::NAME));
        }
        schema
    }
}

/// A number.
pub fn number() -> Value {
    json!({"type": "number"})
}

/// An integer.
pub fn integer() -> Value {
    json!({"type": "integer"})
}

/// A string.
pub fn string() -> Value {
    json!({"type": "string"})
}

/// A boolean.
pub fn boolean() -> Value {
    json!({"type": "boolean"})
}

/// An array of `items`.
pub fn array(items: Value) -> Value {
    json!({"type": "array", "items": items})
}

/// An object with exactly the `fields` given, all required.
pub fn object(fields: &[(&str, Value)]) -> Value {
    object_with_optional(fields, &[])
}

/// An object with the `required` fields and any of the `optional` ones, no others.
pub fn object_with_optional(required: &[(&str, Value)], optional: &[(&str, Value)]) -> Value {
    let properties: Map<String, Value> = required
        .iter()
        .chain(optional)
        .map(|(name, schema)| (name.to_string(), schema.clone()))
        .collect();
    let names: Vec<&str> = required.iter().map(|(name, _)| *name).collect();
    json!({"type": "object", "properties": properties, "required": names,
           "additionalProperties": false})
}

impl Schema for Time {
    fn schema() -> Value {
        object(&[("sec", integer()), ("nsec", integer())])
    }
}

impl Schema for Vector3 {
    fn schema() -> Value {
        object(&[("x", number()), ("y", number()), ("z", number())])
    }
}

impl Schema for Quaternion {
    fn schema() -> Value {
        object(&[
            ("x", number()),
            ("y", number()),
            ("z", number()),
            ("w", number()),
        ])
    }
}

impl Schema for Pose {
    fn schema() -> Value {
        object(&[
            ("position", Vector3::schema()),
            ("orientation", Quaternion::schema()),
        ])
    }
}

impl Schema for Color {
    fn schema() -> Value {
        object(&[
            ("r", number()),
            ("g", number()),
            ("b", number()),
            ("a", number()),
        ])
    }
}

impl Schema for PoseInFrame {
    fn schema() -> Value {
        object(&[
            ("timestamp", Time::schema()),
            ("frame_id", string()),
            ("pose", Pose::schema()),
        ])
    }
}

impl Message for PoseInFrame {
    const NAME: &'static str = "foxglove.PoseInFrame";
}

impl Schema for Log {
    fn schema() -> Value {
        object(&[
            ("timestamp", Time::schema()),
            (
                "level",
                json!({"type": "integer", "enum": [0, 1, 2, 3, 4, 5]}),
            ),
            ("message", string()),
            ("name", string()),
            ("file", string()),
            ("line", integer()),
        ])
    }
}

impl Message for Log {
    const NAME: &'static str = "foxglove.Log";
}

impl Schema for FrameTransform {
    fn schema() -> Value {
        object(&[
            ("timestamp", Time::schema()),
            ("parent_frame_id", string()),
            ("child_frame_id", string()),
            ("translation", Vector3::schema()),
            ("rotation", Quaternion::schema()),
        ])
    }
}

impl Schema for FrameTransforms {
    fn schema() -> Value {
        object(&[("transforms", array(FrameTransform::schema()))])
    }
}

impl Message for FrameTransforms {
    const NAME: &'static str = "foxglove.FrameTransforms";
}

impl Schema for Solid {
    fn schema() -> Value {
        object(&[
            ("pose", Pose::schema()),
            ("size", Vector3::schema()),
            ("color", Color::schema()),
        ])
    }
}

impl Schema for Cylinder {
    fn schema() -> Value {
        object(&[
            ("pose", Pose::schema()),
            ("size", Vector3::schema()),
            ("bottom_scale", number()),
            ("top_scale", number()),
            ("color", Color::schema()),
        ])
    }
}

impl Schema for Arrow {
    fn schema() -> Value {
        object(&[
            ("pose", Pose::schema()),
            ("shaft_length", number()),
            ("shaft_diameter", number()),
            ("head_length", number()),
            ("head_diameter", number()),
            ("color", Color::schema()),
        ])
    }
}

impl Schema for Line {
    fn schema() -> Value {
        object(&[
            ("type", json!({"type": "integer", "enum": [0, 1, 2]})),
            ("pose", Pose::schema()),
            ("thickness", number()),
            ("scale_invariant", boolean()),
            ("points", array(Vector3::schema())),
            ("color", Color::schema()),
            ("colors", array(Color::schema())),
            ("indices", array(integer())),
        ])
    }
}

impl Schema for TriangleList {
    fn schema() -> Value {
        object(&[
            ("pose", Pose::schema()),
            ("points", array(Vector3::schema())),
            ("color", Color::schema()),
            ("colors", array(Color::schema())),
            ("indices", array(integer())),
        ])
    }
}

impl Schema for Text {
    fn schema() -> Value {
        object(&[
            ("pose", Pose::schema()),
            ("billboard", boolean()),
            ("font_size", number()),
            ("scale_invariant", boolean()),
            ("color", Color::schema()),
            ("text", string()),
        ])
    }
}

impl Schema for Model {
    fn schema() -> Value {
        object(&[
            ("pose", Pose::schema()),
            ("scale", Vector3::schema()),
            ("color", Color::schema()),
            ("override_color", boolean()),
            ("url", string()),
            ("media_type", string()),
            ("data", string()),
        ])
    }
}

impl Schema for KeyValuePair {
    fn schema() -> Value {
        object(&[("key", string()), ("value", string())])
    }
}

impl Schema for SceneEntity {
    fn schema() -> Value {
        object(&[
            ("timestamp", Time::schema()),
            ("frame_id", string()),
            ("id", string()),
            ("lifetime", Time::schema()),
            ("frame_locked", boolean()),
            ("metadata", array(KeyValuePair::schema())),
            ("arrows", array(Arrow::schema())),
            ("cubes", array(Solid::schema())),
            ("spheres", array(Solid::schema())),
            ("cylinders", array(Cylinder::schema())),
            ("lines", array(Line::schema())),
            ("triangles", array(TriangleList::schema())),
            ("texts", array(Text::schema())),
            ("models", array(Model::schema())),
        ])
    }
}

impl Schema for SceneEntityDeletion {
    fn schema() -> Value {
        object(&[
            ("timestamp", Time::schema()),
            ("type", json!({"type": "integer", "enum": [0, 1]})),
            ("id", string()),
        ])
    }
}

impl Schema for SceneUpdate {
    fn schema() -> Value {
        object(&[
            ("deletions", array(SceneEntityDeletion::schema())),
            ("entities", array(SceneEntity::schema())),
        ])
    }
}

impl Message for SceneUpdate {
    const NAME: &'static str = "foxglove.SceneUpdate";
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields<T: Schema>() -> Vec<String> {
        T::schema()["properties"]
            .as_object()
            .unwrap()
            .keys()
            .cloned()
            .collect()
    }

    /// Foxglove's own field names (its `schemas/` definitions), in its order: a field renamed
    /// here and in the struct alike would still not be Foxglove's.
    #[test]
    fn schemas_name_the_fields_foxglove_defines() {
        let expected: [(&str, Vec<String>, &str); 16] = [
            ("Time", fields::<Time>(), "sec nsec"),
            ("Vector3", fields::<Vector3>(), "x y z"),
            ("Quaternion", fields::<Quaternion>(), "x y z w"),
            ("Pose", fields::<Pose>(), "position orientation"),
            ("Color", fields::<Color>(), "r g b a"),
            (
                "PoseInFrame",
                fields::<PoseInFrame>(),
                "timestamp frame_id pose",
            ),
            (
                "Log",
                fields::<Log>(),
                "timestamp level message name file line",
            ),
            (
                "FrameTransform",
                fields::<FrameTransform>(),
                "timestamp parent_frame_id child_frame_id translation rotation",
            ),
            ("CubePrimitive", fields::<Solid>(), "pose size color"),
            (
                "CylinderPrimitive",
                fields::<Cylinder>(),
                "pose size bottom_scale top_scale color",
            ),
            (
                "ArrowPrimitive",
                fields::<Arrow>(),
                "pose shaft_length shaft_diameter head_length head_diameter color",
            ),
            (
                "LinePrimitive",
                fields::<Line>(),
                "type pose thickness scale_invariant points color colors indices",
            ),
            (
                "TriangleListPrimitive",
                fields::<TriangleList>(),
                "pose points color colors indices",
            ),
            (
                "TextPrimitive",
                fields::<Text>(),
                "pose billboard font_size scale_invariant color text",
            ),
            (
                "ModelPrimitive",
                fields::<Model>(),
                "pose scale color override_color url media_type data",
            ),
            (
                "SceneEntity",
                fields::<SceneEntity>(),
                "timestamp frame_id id lifetime frame_locked metadata arrows cubes spheres \
                 cylinders lines triangles texts models",
            ),
        ];
        for (name, ours, foxglove) in expected {
            assert_eq!(ours.join(" "), foxglove, "{name}");
        }
        assert_eq!(fields::<SceneUpdate>(), ["deletions", "entities"]);
        assert_eq!(fields::<SceneEntityDeletion>(), ["timestamp", "type", "id"]);
        assert_eq!(fields::<FrameTransforms>(), ["transforms"]);
    }

    #[test]
    fn an_object_requires_its_fields_and_no_others() {
        let s = object_with_optional(&[("a", number())], &[("b", string())]);
        assert_eq!(s["required"], json!(["a"]));
        assert_eq!(s["additionalProperties"], json!(false));
        assert_eq!(s["properties"]["b"], string());
        assert_eq!(Log::titled_schema()["title"], "foxglove.Log");
    }
}
