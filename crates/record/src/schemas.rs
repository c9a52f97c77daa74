//! Schemas embedded in every recording, and the declaration of scalar (plot) topics.

use serde::{Deserialize, Serialize};
use serde_json::{json, Map, Value};

use crate::error::{RecordError, Result};

/// Schema name Foxglove's 3D panel recognises for scene entities.
pub const SCENE_UPDATE_SCHEMA: &str = "foxglove.SceneUpdate";
/// Schema name Foxglove recognises for transforms.
pub const FRAME_TRANSFORMS_SCHEMA: &str = "foxglove.FrameTransforms";
/// Schema encoding of every schema in the file.
pub const SCHEMA_ENCODING: &str = "jsonschema";
/// Message encoding of every channel in the file.
pub const MESSAGE_ENCODING: &str = "json";

/// JSON Schema text of `foxglove.SceneUpdate` as esrl writes it (boxes, spheres, cylinders),
/// with `required` lists naming every field esrl always writes.
pub const SCENE_UPDATE_SCHEMA_JSON: &str = include_str!("../schemas/foxglove.SceneUpdate.json");
/// JSON Schema text of `foxglove.FrameTransforms`, with `required` lists.
pub const FRAME_TRANSFORMS_SCHEMA_JSON: &str =
    include_str!("../schemas/foxglove.FrameTransforms.json");

/// A plottable topic: every message is `{"timestamp": {sec, nsec}, field: number, ...}`, so
/// Foxglove's Plot panel takes paths like `/esrl/joints/torque.left_knee`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ScalarTopic {
    /// Topic name, starting with `/` (e.g. `/esrl/joints/torque`).
    pub topic: String,
    /// Schema name (e.g. `esrl.joints.torque`).
    pub schema_name: String,
    /// Field names: ASCII letters, digits and `_`, not starting with a digit, not `timestamp`.
    pub fields: Vec<String>,
}

impl ScalarTopic {
    /// A topic whose schema name is derived from the topic: `/esrl/joints/torque` →
    /// `esrl.joints.torque`, `/reward` → `esrl.reward`.
    pub fn new(topic: &str, fields: &[&str]) -> Self {
        let dotted = topic.trim_start_matches('/').replace('/', ".");
        let schema_name = if dotted.starts_with("esrl.") {
            dotted
        } else {
            format!("esrl.{dotted}")
        };
        Self {
            topic: topic.to_string(),
            schema_name,
            fields: fields.iter().map(|f| f.to_string()).collect(),
        }
    }

    /// Checks the topic, schema and field names (see the field docs).
    pub fn validate(&self) -> Result<()> {
        let bad = |why: String| RecordError::InvalidTopic {
            topic: self.topic.clone(),
            why,
        };
        if !self.topic.starts_with('/') || self.topic.len() < 2 {
            return Err(bad("topic must start with `/` and name something".into()));
        }
        if self.schema_name.is_empty() {
            return Err(bad("empty schema name".into()));
        }
        let mut seen = std::collections::HashSet::new();
        for f in &self.fields {
            if !is_identifier(f) {
                return Err(bad(format!(
                    "field `{f}` must be ASCII letters, digits and `_`, not starting with a digit"
                )));
            }
            if f == "timestamp" {
                return Err(bad("field `timestamp` is reserved".into()));
            }
            if !seen.insert(f.as_str()) {
                return Err(bad(format!("duplicate field `{f}`")));
            }
        }
        Ok(())
    }

    /// The topic's JSON Schema: an object with `timestamp` and one number per field, all
    /// required.
    pub fn schema(&self) -> Value {
        let mut properties = Map::new();
        properties.insert(
            "timestamp".into(),
            json!({
                "title": "time",
                "description": "Simulated time of the step",
                "type": "object",
                "properties": {
                    "sec": {"type": "integer", "minimum": 0},
                    "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}
                },
                "required": ["sec", "nsec"]
            }),
        );
        for f in &self.fields {
            properties.insert(f.clone(), json!({"type": "number"}));
        }
        let mut required = vec![Value::from("timestamp")];
        required.extend(self.fields.iter().map(|f| Value::from(f.as_str())));
        json!({
            "title": self.schema_name,
            "description": format!("esrl scalar channel {}", self.topic),
            "type": "object",
            "properties": properties,
            "required": required,
        })
    }
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}
