//! Small hand-written JSON Schema checks, enough for the schemas this crate writes: do the
//! messages carry every `required` field (with the declared type), and would Foxglove's
//! `jsonschema` parser accept the schema.

use serde_json::Value;

/// Problems of `message` against `schema`: every name in a `required` list must be present,
/// recursively through `properties` and array `items`, and present values must have the
/// declared `type` (`object`, `array`, `number`, `integer`, `string`, `boolean`) or be one of
/// the `oneOf` constants. Empty when the message conforms. Paths look like
/// `entities[0].cubes[1].pose.orientation.w`.
pub fn message_problems(schema: &Value, message: &Value) -> Vec<String> {
    let mut out = Vec::new();
    walk_message(schema, message, "$", &mut out);
    out
}

fn walk_message(schema: &Value, value: &Value, path: &str, out: &mut Vec<String>) {
    if let Some(alternatives) = schema["oneOf"].as_array() {
        if !alternatives.iter().any(|a| a.get("const") == Some(value)) {
            out.push(format!("{path}: {value} is none of the oneOf constants"));
        }
        return;
    }
    let ok = match schema["type"].as_str() {
        Some("object") => {
            let Some(obj) = value.as_object() else {
                out.push(format!("{path}: expected an object, got {value}"));
                return;
            };
            for name in schema["required"].as_array().into_iter().flatten() {
                if let Some(name) = name.as_str() {
                    if !obj.contains_key(name) {
                        out.push(format!("{path}.{name}: required field missing"));
                    }
                }
            }
            if let Some(props) = schema["properties"].as_object() {
                for (name, sub) in props {
                    if let Some(v) = obj.get(name) {
                        walk_message(sub, v, &format!("{path}.{name}"), out);
                    }
                }
            }
            true
        }
        Some("array") => {
            let Some(items) = value.as_array() else {
                out.push(format!("{path}: expected an array, got {value}"));
                return;
            };
            for (i, item) in items.iter().enumerate() {
                walk_message(&schema["items"], item, &format!("{path}[{i}]"), out);
            }
            true
        }
        Some("number") => value.is_number(),
        Some("integer") => value.is_u64() || value.is_i64(),
        Some("string") => value.is_string(),
        Some("boolean") => value.is_boolean(),
        _ => true,
    };
    if !ok {
        out.push(format!("{path}: {value} is not of type {}", schema["type"]));
    }
}

/// Problems Foxglove's `jsonschema` parser would raise on `schema` (its `parseJsonSchema`):
/// every object needs `"type": "object"` and `properties`; every property needs a `type` among
/// boolean/string/number/integer/object/array or `oneOf` numeric constants; array `items` need
/// one of boolean/string/number/integer/object; only `base64` as `contentEncoding`.
pub fn foxglove_schema_problems(schema: &Value) -> Vec<String> {
    let mut out = Vec::new();
    walk_schema_object(schema, "$", &mut out);
    out
}

fn walk_schema_object(schema: &Value, path: &str, out: &mut Vec<String>) {
    if schema["type"] != "object" {
        out.push(format!("{path}: expected \"type\": \"object\""));
        return;
    }
    let Some(props) = schema["properties"].as_object() else {
        out.push(format!("{path}: object without properties"));
        return;
    };
    for (name, field) in props {
        let p = format!("{path}.{name}");
        if let Some(alternatives) = field["oneOf"].as_array() {
            if !alternatives.iter().all(|a| a["const"].is_number()) {
                out.push(format!("{p}: oneOf alternatives must be numeric constants"));
            }
            continue;
        }
        match field["type"].as_str() {
            Some("boolean" | "number" | "integer") => {}
            Some("string") => match field.get("contentEncoding") {
                None => {}
                Some(e) if e == "base64" => {}
                Some(e) => out.push(format!("{p}: unsupported contentEncoding {e}")),
            },
            Some("object") => walk_schema_object(field, &p, out),
            Some("array") => match field["items"]["type"].as_str() {
                Some("boolean" | "number" | "integer") => {}
                Some("string") if field["items"].get("contentEncoding").is_none() => {}
                Some("object") => walk_schema_object(&field["items"], &format!("{p}[]"), out),
                other => out.push(format!("{p}: unsupported array item type {other:?}")),
            },
            other => out.push(format!("{p}: unsupported type {other:?}")),
        }
    }
}
