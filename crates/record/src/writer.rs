//! The streaming MCAP writer.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

use mcap::records::{MessageHeader, Metadata};
use mcap::{WriteOptions, Writer};
use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;

use crate::error::{RecordError, Result};
use crate::messages::{scene_update, FrameTransform, FrameTransforms, Time};
use crate::scene::{Frame, Pose, Scene};
use crate::schemas::{
    ScalarTopic, FRAME_TRANSFORMS_SCHEMA, FRAME_TRANSFORMS_SCHEMA_JSON, MESSAGE_ENCODING,
    SCENE_UPDATE_SCHEMA, SCENE_UPDATE_SCHEMA_JSON, SCHEMA_ENCODING,
};

/// The fixed frame: every link frame is a child of it.
pub const WORLD_FRAME: &str = "world";
/// Topic of the `foxglove.SceneUpdate` (written once, at the first frame's time).
pub const SCENE_TOPIC: &str = "/scene";
/// Topic of the `foxglove.FrameTransforms` (one message per frame).
pub const TRANSFORMS_TOPIC: &str = "/tf";
/// Name of the MCAP metadata record holding [`RecordOptions::metadata`].
pub const METADATA_NAME: &str = "esrl";

/// Options of [`RolloutWriter`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RecordOptions {
    /// Added to every frame's `time_ns` for the message and log times (default 0: the recording
    /// starts at the Unix epoch, i.e. the timeline shows time since reset).
    pub time_offset_ns: u64,
    /// Key/value pairs stored in one MCAP metadata record named [`METADATA_NAME`] (agent, seed,
    /// checkpoint, ...); none is written when empty.
    pub metadata: BTreeMap<String, String>,
}

/// What a finished recording holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordingStats {
    /// Frames written.
    pub frames: usize,
    /// Messages written on all channels.
    pub messages: u64,
}

/// Writes a rollout as MCAP, frame by frame: channel [`SCENE_TOPIC`] gets the scene once,
/// [`TRANSFORMS_TOPIC`] the link poses every frame, and each [`ScalarTopic`] one message per
/// frame. Chunks are uncompressed (the crate builds mcap without zstd/lz4).
pub struct RolloutWriter<W: Write + Seek> {
    mcap: Writer<W>,
    scene: Scene,
    topics: Vec<ScalarTopic>,
    scene_channel: u16,
    tf_channel: u16,
    scalar_channels: Vec<u16>,
    time_offset_ns: u64,
    last_time_ns: Option<u64>,
    frames: usize,
    rename: Option<(PathBuf, PathBuf)>,
}

impl RolloutWriter<BufWriter<File>> {
    /// Creates `path` (written as `path.partial`, renamed by [`RolloutWriter::finish_file`],
    /// so a crash never leaves a truncated file under the final name).
    pub fn create(
        path: &Path,
        scene: &Scene,
        topics: &[ScalarTopic],
        options: RecordOptions,
    ) -> Result<Self> {
        let mut partial = path.as_os_str().to_owned();
        partial.push(".partial");
        let partial = PathBuf::from(partial);
        let file = File::create(&partial).map_err(|source| RecordError::Io {
            path: partial.clone(),
            source,
        })?;
        let mut w = Self::new(BufWriter::new(file), scene, topics, options)?;
        w.rename = Some((partial, path.to_path_buf()));
        Ok(w)
    }

    /// Finishes the file, syncs it to disk and renames it to the path given to
    /// [`RolloutWriter::create`].
    pub fn finish_file(self) -> Result<RecordingStats> {
        let rename = self.rename.clone();
        let (buf, stats) = self.finish()?;
        let Some((partial, path)) = rename else {
            return Ok(stats);
        };
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| RecordError::Io { path, source }
        };
        let file = buf.into_inner().map_err(|e| RecordError::Io {
            path: partial.clone(),
            source: e.into_error(),
        })?;
        file.sync_all().map_err(io(&partial))?;
        std::fs::rename(&partial, &path).map_err(io(&path))?;
        Ok(stats)
    }
}

impl<W: Write + Seek> RolloutWriter<W> {
    /// Starts a recording in `w`: validates the scene and topics, writes the header, the
    /// schemas (their JSON text is the schema data), the channels and the metadata.
    pub fn new(
        w: W,
        scene: &Scene,
        topics: &[ScalarTopic],
        options: RecordOptions,
    ) -> Result<Self> {
        scene.validate()?;
        let mut seen = std::collections::HashSet::from([SCENE_TOPIC, TRANSFORMS_TOPIC]);
        for t in topics {
            t.validate()?;
            if !seen.insert(t.topic.as_str()) {
                return Err(RecordError::InvalidTopic {
                    topic: t.topic.clone(),
                    why: "topic used twice (or reserved for the scene/transforms)".into(),
                });
            }
        }
        let mut mcap = WriteOptions::new()
            .compression(None)
            .profile("")
            .create(w)?;
        let no_meta = BTreeMap::new();
        let scene_schema = mcap.add_schema(
            SCENE_UPDATE_SCHEMA,
            SCHEMA_ENCODING,
            SCENE_UPDATE_SCHEMA_JSON.as_bytes(),
        )?;
        let scene_channel =
            mcap.add_channel(scene_schema, SCENE_TOPIC, MESSAGE_ENCODING, &no_meta)?;
        let tf_schema = mcap.add_schema(
            FRAME_TRANSFORMS_SCHEMA,
            SCHEMA_ENCODING,
            FRAME_TRANSFORMS_SCHEMA_JSON.as_bytes(),
        )?;
        let tf_channel =
            mcap.add_channel(tf_schema, TRANSFORMS_TOPIC, MESSAGE_ENCODING, &no_meta)?;
        let mut scalar_channels = Vec::with_capacity(topics.len());
        for t in topics {
            let schema = serde_json::to_vec(&t.schema()).map_err(|source| RecordError::Json {
                context: format!("schema of {}", t.topic),
                source,
            })?;
            let id = mcap.add_schema(&t.schema_name, SCHEMA_ENCODING, &schema)?;
            scalar_channels.push(mcap.add_channel(id, &t.topic, MESSAGE_ENCODING, &no_meta)?);
        }
        if !options.metadata.is_empty() {
            mcap.write_metadata(&Metadata {
                name: METADATA_NAME.into(),
                metadata: options.metadata.clone(),
            })?;
        }
        Ok(Self {
            mcap,
            scene: scene.clone(),
            topics: topics.to_vec(),
            scene_channel,
            tf_channel,
            scalar_channels,
            time_offset_ns: options.time_offset_ns,
            last_time_ns: None,
            frames: 0,
            rename: None,
        })
    }

    /// Appends one frame (the first one also publishes the scene at its time). Nothing is
    /// written when the frame is refused: wrong number of link poses or scalar values, NaN/inf,
    /// a zero quaternion, or a time not after the previous frame's.
    pub fn write_frame(&mut self, frame: &Frame) -> Result<()> {
        let index = self.frames;
        let bad = |what: String, why: String| RecordError::InvalidFrame {
            frame: index,
            what,
            why,
        };
        if let Some(last) = self.last_time_ns {
            if frame.time_ns <= last {
                return Err(bad(
                    "time_ns".into(),
                    format!("{} is not after the previous frame's {last}", frame.time_ns),
                ));
            }
        }
        let log_time = frame
            .time_ns
            .checked_add(self.time_offset_ns)
            .ok_or_else(|| {
                bad(
                    "time_ns".into(),
                    format!(
                        "{} + offset {} overflows u64",
                        frame.time_ns, self.time_offset_ns
                    ),
                )
            })?;
        if frame.link_poses.len() != self.scene.links.len() {
            return Err(bad(
                "link_poses".into(),
                format!(
                    "{} poses for {} links",
                    frame.link_poses.len(),
                    self.scene.links.len()
                ),
            ));
        }
        let poses = frame
            .link_poses
            .iter()
            .enumerate()
            .map(|(i, p)| {
                p.normalized()
                    .map_err(|why| bad(format!("link_poses[{i}]"), why))
            })
            .collect::<Result<Vec<Pose>>>()?;
        if frame.scalars.len() != self.topics.len() {
            return Err(bad(
                "scalars".into(),
                format!(
                    "{} value lists for {} topics",
                    frame.scalars.len(),
                    self.topics.len()
                ),
            ));
        }
        for (topic, values) in self.topics.iter().zip(&frame.scalars) {
            if values.len() != topic.fields.len() {
                return Err(bad(
                    topic.topic.clone(),
                    format!("{} values for {} fields", values.len(), topic.fields.len()),
                ));
            }
            if let Some(j) = values.iter().position(|v| !v.is_finite()) {
                return Err(bad(
                    format!("{}.{}", topic.topic, topic.fields[j]),
                    format!("non-finite value {}", values[j]),
                ));
            }
        }

        let time = Time::from_ns(log_time);
        let sequence = u32::try_from(index).unwrap_or(u32::MAX);
        if index == 0 {
            let update = scene_update(&self.scene, time);
            let data = to_json(&update, SCENE_TOPIC)?;
            self.write(self.scene_channel, 0, log_time, &data)?;
        }
        let transforms = FrameTransforms {
            transforms: self
                .scene
                .links
                .iter()
                .zip(&poses)
                .map(|(link, pose)| FrameTransform {
                    timestamp: time,
                    parent_frame_id: WORLD_FRAME,
                    child_frame_id: &link.name,
                    translation: pose.translation.into(),
                    rotation: pose.rotation.into(),
                })
                .collect(),
        };
        let data = to_json(&transforms, TRANSFORMS_TOPIC)?;
        self.write(self.tf_channel, sequence, log_time, &data)?;
        for k in 0..self.topics.len() {
            let topic = &self.topics[k];
            let data = to_json(
                &ScalarMessage {
                    timestamp: time,
                    fields: &topic.fields,
                    values: &frame.scalars[k],
                },
                &topic.topic,
            )?;
            self.write(self.scalar_channels[k], sequence, log_time, &data)?;
        }
        self.last_time_ns = Some(frame.time_ns);
        self.frames += 1;
        Ok(())
    }

    fn write(&mut self, channel_id: u16, sequence: u32, time: u64, data: &[u8]) -> Result<()> {
        self.mcap.write_to_known_channel(
            &MessageHeader {
                channel_id,
                sequence,
                log_time: time,
                publish_time: time,
            },
            data,
        )?;
        Ok(())
    }

    /// Number of frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Writes the summary section and footer; returns the underlying writer and the counts.
    pub fn finish(mut self) -> Result<(W, RecordingStats)> {
        let summary = self.mcap.finish()?;
        let messages = summary.stats.map_or(0, |s| s.message_count);
        let frames = self.frames;
        Ok((self.mcap.into_inner(), RecordingStats { frames, messages }))
    }
}

fn to_json<T: Serialize>(value: &T, topic: &str) -> Result<Vec<u8>> {
    serde_json::to_vec(value).map_err(|source| RecordError::Json {
        context: topic.to_string(),
        source,
    })
}

/// `{"timestamp": {...}, field: value, ...}` with fields in declaration order.
struct ScalarMessage<'a> {
    timestamp: Time,
    fields: &'a [String],
    values: &'a [f64],
}

impl Serialize for ScalarMessage<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.fields.len() + 1))?;
        map.serialize_entry("timestamp", &self.timestamp)?;
        for (f, v) in self.fields.iter().zip(self.values) {
            map.serialize_entry(f, v)?;
        }
        map.end()
    }
}

/// Writes a whole rollout to `path` (atomically, see [`RolloutWriter::create`]).
pub fn write_recording(
    path: &Path,
    scene: &Scene,
    topics: &[ScalarTopic],
    frames: &[Frame],
    options: RecordOptions,
) -> Result<RecordingStats> {
    let mut w = RolloutWriter::create(path, scene, topics, options)?;
    for f in frames {
        w.write_frame(f)?;
    }
    w.finish_file()
}
