//! Reading recordings back: channels, a topic's JSON messages, a scalar topic as columns.

use std::path::Path;

use mcap::{MessageStream, Summary};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{RecordError, Result};

/// A channel of a recording, with its schema.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChannelInfo {
    /// Channel id in the file.
    pub id: u16,
    /// Topic name.
    pub topic: String,
    /// Message encoding (`json` for esrl recordings).
    pub message_encoding: String,
    /// Schema name, e.g. `foxglove.SceneUpdate`.
    pub schema_name: Option<String>,
    /// Schema encoding (`jsonschema` for esrl recordings).
    pub schema_encoding: Option<String>,
    /// Schema data as text.
    pub schema: Option<String>,
    /// Messages on the channel according to the file's statistics.
    pub message_count: u64,
}

/// One message of a channel, decoded from JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordedMessage {
    /// MCAP log time (ns).
    pub log_time: u64,
    /// MCAP publish time (ns).
    pub publish_time: u64,
    /// Sequence number.
    pub sequence: u32,
    /// The decoded message.
    pub data: Value,
}

/// A scalar topic as columns, e.g. for NumPy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScalarSeries {
    /// Topic name.
    pub topic: String,
    /// Field names, in the order of the schema's `required` list (the declaration order).
    pub fields: Vec<String>,
    /// Log time of each message (ns).
    pub time_ns: Vec<u64>,
    /// `values[step][field]`.
    pub values: Vec<Vec<f64>>,
}

/// Reads a whole file into memory (recordings of one rollout are a few MB).
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| RecordError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The channels listed in the file's summary section, sorted by id.
pub fn channels(mcap: &[u8]) -> Result<Vec<ChannelInfo>> {
    let summary = Summary::read(mcap)?
        .ok_or_else(|| RecordError::Read("the file has no summary section".into()))?;
    let counts = summary
        .stats
        .as_ref()
        .map(|s| s.channel_message_counts.clone())
        .unwrap_or_default();
    let mut out: Vec<ChannelInfo> = summary
        .channels
        .values()
        .map(|c| ChannelInfo {
            id: c.id,
            topic: c.topic.clone(),
            message_encoding: c.message_encoding.clone(),
            schema_name: c.schema.as_ref().map(|s| s.name.clone()),
            schema_encoding: c.schema.as_ref().map(|s| s.encoding.clone()),
            schema: c
                .schema
                .as_ref()
                .map(|s| String::from_utf8_lossy(&s.data).into_owned()),
            message_count: counts.get(&c.id).copied().unwrap_or(0),
        })
        .collect();
    out.sort_by_key(|c| c.id);
    Ok(out)
}

/// All messages on `topic`, in file order, JSON-decoded. Errors if no channel has that topic.
pub fn read_channel(mcap: &[u8], topic: &str) -> Result<Vec<RecordedMessage>> {
    let known = channels(mcap)?;
    if !known.iter().any(|c| c.topic == topic) {
        let topics: Vec<&str> = known.iter().map(|c| c.topic.as_str()).collect();
        return Err(RecordError::Read(format!(
            "no channel `{topic}`; the file has {topics:?}"
        )));
    }
    let mut out = Vec::new();
    for message in MessageStream::new(mcap)? {
        let message = message?;
        if message.channel.topic != topic {
            continue;
        }
        let data = serde_json::from_slice(&message.data).map_err(|source| RecordError::Json {
            context: format!("{topic} message {}", message.sequence),
            source,
        })?;
        out.push(RecordedMessage {
            log_time: message.log_time,
            publish_time: message.publish_time,
            sequence: message.sequence,
            data,
        });
    }
    Ok(out)
}

/// [`read_channel`] on a file.
pub fn read_channel_file(path: &Path, topic: &str) -> Result<Vec<RecordedMessage>> {
    read_channel(&read_file(path)?, topic)
}

/// A scalar topic (see [`ScalarTopic`](crate::ScalarTopic)) as columns.
pub fn read_scalars(mcap: &[u8], topic: &str) -> Result<ScalarSeries> {
    let info = channels(mcap)?
        .into_iter()
        .find(|c| c.topic == topic)
        .ok_or_else(|| RecordError::Read(format!("no channel `{topic}`")))?;
    let schema: Value =
        serde_json::from_str(info.schema.as_deref().unwrap_or("")).map_err(|source| {
            RecordError::Json {
                context: format!("schema of {topic}"),
                source,
            }
        })?;
    let fields: Vec<String> = schema["required"]
        .as_array()
        .map(|r| {
            r.iter()
                .filter_map(Value::as_str)
                .filter(|f| *f != "timestamp")
                .map(String::from)
                .collect()
        })
        .unwrap_or_default();
    let mut series = ScalarSeries {
        topic: topic.into(),
        fields,
        time_ns: Vec::new(),
        values: Vec::new(),
    };
    for m in read_channel(mcap, topic)? {
        let row = series
            .fields
            .iter()
            .map(|f| {
                m.data[f].as_f64().ok_or_else(|| {
                    RecordError::Read(format!(
                        "{topic} message {}: field `{f}` is not a number",
                        m.sequence
                    ))
                })
            })
            .collect::<Result<Vec<f64>>>()?;
        series.time_ns.push(m.log_time);
        series.values.push(row);
    }
    Ok(series)
}
