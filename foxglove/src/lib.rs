//! Foxglove messages as AKL writes them: typed JSON, with their JSON schemas, on typed MCAP
//! channels.
//!
//! The demonstration recorder (`akl-learn`) and the trial tracer (`akl-exec`) both write MCAP
//! files for Foxglove with JSON-encoded messages. This crate holds what they share:
//! - the messages, at the crate root: serde structs of the Foxglove schemas they use (`foxglove.Log`,
//!   `foxglove.PoseInFrame`, `foxglove.FrameTransforms`, `foxglove.SceneUpdate` and the
//!   primitives of a scene entity), with the field names and order Foxglove defines;
//! - [`schema`]: the [`Message`] trait (a schema name and a JSON schema per message type) and
//!   the builders of JSON schemas, which a crate's own message types (`akl.Gripper`, ...) use;
//! - [`McapWriter`]: an MCAP writer whose channels are typed by their message, so a message can
//!   only be written on a channel of its schema, and the time stamp [`Time::at`].
//!
//! Every schema lists its fields as required and allows no others, so a message with a
//! misnamed or missing field breaks the schema written beside it; with the `check` feature,
//! `check_mcap` validates every message of a file against its channel's schema (the recorder's
//! and the tracer's tests do).
//!
//! The `foxglove` crate was not used: it writes these messages as protobuf (its serde support
//! is for debugging), and the demonstrations AKL reads back are JSON.

#[cfg(feature = "check")]
mod check;
mod messages;
pub mod schema;
mod writer;

#[cfg(feature = "check")]
pub use check::{check_mcap, Violation};
pub use messages::{
    Arrow, Color, Cylinder, FrameTransform, FrameTransforms, KeyValuePair, Line, LineType, Log,
    LogLevel, Model, Pose, PoseInFrame, Quaternion, SceneEntity, SceneEntityDeletion, SceneUpdate,
    Solid, Text, Time, TriangleList, Vector3,
};
pub use schema::{Message, Schema};
pub use writer::{Channel, Encoded, McapWriter, WriteError};
