//! MCAP trajectories. Four JSON-encoded channels, each with a declared JSON Schema:
//! `/obs` (`episode`, `step`, `obs`), `/action` (`normalised`, `physical`), `/reward`
//! (`reward`, `terminated`, `truncated`) and `/info` (every numeric and text info value); step 0
//! of each episode is the reset's observation. A metadata record `manifest` holds the env spec,
//! its hash, seeds, policy and code version. Chunks are zstd-compressed and closed at the end
//! of every episode, so a killed writer loses at most the episode in progress (`recover`
//! salvages every complete chunk); `finish` writes the summary and index.
//! With [`TrajectoryWriter::with_fields`], a fifth channel `/field` holds flow-field snapshots
//! (`foxglove.Grid`, see [`super::field`]) at reset and every k actions.
//! Log times are simulated time: the file's global step count times the control interval.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use hgym_agents::{Info, StepResult};
use mcap::records::{MessageHeader, Metadata};
use mcap::write::Writer;
use serde_json::json;

use super::DataError;

const OBS_SCHEMA: &str = r#"{"type":"object","properties":{"episode":{"type":"integer"},"step":{"type":"integer"},"obs":{"type":"array","items":{"type":"number"}}},"required":["episode","step","obs"]}"#;
const ACTION_SCHEMA: &str = r#"{"type":"object","properties":{"episode":{"type":"integer"},"step":{"type":"integer"},"normalised":{"type":"array","items":{"type":"number"}},"physical":{"type":"array","items":{"type":"number"}}},"required":["episode","step","normalised","physical"]}"#;
const REWARD_SCHEMA: &str = r#"{"type":"object","properties":{"episode":{"type":"integer"},"step":{"type":"integer"},"reward":{"type":"number"},"terminated":{"type":"boolean"},"truncated":{"type":"boolean"}},"required":["episode","step","reward","terminated","truncated"]}"#;
const INFO_SCHEMA: &str = r#"{"type":"object","properties":{"episode":{"type":"integer"},"step":{"type":"integer"},"values":{"type":"object","additionalProperties":{"type":["number","null"]}},"text":{"type":"object","additionalProperties":{"type":"string"}}},"required":["episode","step","values","text"]}"#;

pub struct TrajectoryWriter {
    writer: Option<Writer<BufWriter<File>>>,
    channels: [u16; 5],
    interval_ns: f64,
    fields_every: u64,
    t: f64,
    global_step: u64,
    episode: u64,
    step: u64,
    sequence: u32,
}

impl TrajectoryWriter {
    /// Creates `path` with the manifest (string key-values) as metadata.
    pub fn create(path: &Path, control_interval: f64, manifest: BTreeMap<String, String>) -> Result<Self, DataError> {
        let file = File::create(path).map_err(DataError::io(path))?;
        let mut w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("hgym")
            .library(format!("hgym {}", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))?;
        let mut channels = [0u16; 5];
        for (k, (topic, schema)) in [
            ("/obs", OBS_SCHEMA),
            ("/action", ACTION_SCHEMA),
            ("/reward", REWARD_SCHEMA),
            ("/info", INFO_SCHEMA),
            ("/field", super::field::SCHEMA),
        ]
        .into_iter()
        .enumerate()
        {
            let name = match topic {
                "/field" => "foxglove.Grid".to_string(),
                _ => format!("hgym{}", topic.replace('/', ".")),
            };
            let sid = w.add_schema(&name, "jsonschema", schema.as_bytes())?;
            channels[k] = w.add_channel(sid, topic, "json", &BTreeMap::new())?;
        }
        w.write_metadata(&Metadata {
            name: "manifest".into(),
            metadata: manifest,
        })?;
        Ok(TrajectoryWriter {
            writer: Some(w),
            channels,
            interval_ns: control_interval * 1e9,
            fields_every: 0,
            t: 0.0,
            global_step: 0,
            episode: 0,
            step: 0,
            sequence: 0,
        })
    }

    /// Flow-field snapshots at each reset and every `every` actions (0: none).
    pub fn with_fields(mut self, every: u64) -> Self {
        self.fields_every = every;
        self
    }

    /// Whether the caller should pass a snapshot of the current state to [`Self::field`].
    pub fn wants_field(&self) -> bool {
        self.fields_every > 0 && self.step.is_multiple_of(self.fields_every)
    }

    /// Writes a flow-field snapshot of the current step.
    pub fn field(&mut self, mut s: super::field::Snapshot) -> Result<(), DataError> {
        (s.episode, s.step, s.t) = (self.episode, self.step, self.t);
        let data = s.encode()?;
        self.put_bytes(4, &data)
    }

    fn put(&mut self, channel: usize, value: serde_json::Value) -> Result<(), DataError> {
        let data = serde_json::to_vec(&value)?;
        self.put_bytes(channel, &data)
    }

    fn put_bytes(&mut self, channel: usize, data: &[u8]) -> Result<(), DataError> {
        let log_time = (self.global_step as f64 * self.interval_ns) as u64;
        self.sequence += 1;
        let w = self.writer.as_mut().ok_or(DataError::Finished)?;
        w.write_to_known_channel(
            &MessageHeader {
                channel_id: self.channels[channel],
                sequence: self.sequence,
                log_time,
                publish_time: log_time,
            },
            data,
        )?;
        Ok(())
    }

    fn info_json(&self, info: &Info) -> serde_json::Value {
        json!({"episode": self.episode, "step": self.step, "values": info.values, "text": info.text})
    }

    /// Step 0 of a new episode: the reset's observation and info.
    pub fn reset(&mut self, obs: &[f64], info: &Info) -> Result<(), DataError> {
        self.step = 0;
        self.t = info.get("t").unwrap_or(0.0);
        self.put(0, json!({"episode": self.episode, "step": 0, "obs": obs}))?;
        let v = self.info_json(info);
        self.put(3, v)
    }

    /// One step: the action taken (normalised; physical values from info `actuation_k`) and
    /// what it returned. Closes the chunk at the episode's end.
    pub fn step(&mut self, action: &[f64], r: &StepResult) -> Result<(), DataError> {
        self.step_with_field(action, r, None::<fn() -> super::field::Snapshot>)
    }

    /// [`Self::step`], plus a flow-field snapshot of the state after the step from `snapshot`
    /// when one is due (see [`Self::with_fields`]); the last step of an episode always has one.
    pub fn step_with_field<F: FnOnce() -> super::field::Snapshot>(
        &mut self,
        action: &[f64],
        r: &StepResult,
        snapshot: Option<F>,
    ) -> Result<(), DataError> {
        self.step += 1;
        self.global_step += 1;
        self.t = r.info.get("t").unwrap_or(f64::NAN);
        let physical: Vec<f64> = (0..action.len())
            .map(|k| r.info.get(&format!("actuation_{k}")).unwrap_or(f64::NAN))
            .collect();
        let (e, k) = (self.episode, self.step);
        self.put(1, json!({"episode": e, "step": k, "normalised": action, "physical": physical}))?;
        self.put(0, json!({"episode": e, "step": k, "obs": r.obs}))?;
        self.put(
            2,
            json!({"episode": e, "step": k, "reward": r.reward, "terminated": r.terminated, "truncated": r.truncated}),
        )?;
        let v = self.info_json(&r.info);
        self.put(3, v)?;
        let last = r.terminated || r.truncated;
        if let Some(f) = snapshot {
            if self.fields_every > 0 && (self.wants_field() || last) {
                self.field(f())?;
            }
        }
        if last {
            self.end_episode()?;
        }
        Ok(())
    }

    /// Closes the current chunk (everything so far survives a kill) and starts a new episode.
    pub fn end_episode(&mut self) -> Result<(), DataError> {
        self.episode += 1;
        self.global_step += 1;
        self.writer.as_mut().ok_or(DataError::Finished)?.flush()?;
        Ok(())
    }

    /// Writes the summary and index; the file is complete.
    pub fn finish(&mut self) -> Result<(), DataError> {
        if let Some(mut w) = self.writer.take() {
            w.finish()?;
        }
        Ok(())
    }
}

impl Drop for TrajectoryWriter {
    fn drop(&mut self) {
        let _ = self.finish();
    }
}

/// What `recover` salvaged.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Recovery {
    pub messages: usize,
    pub metadata: usize,
    /// Bytes up to the end of the last whole record (what could be read).
    pub bytes_read: usize,
    pub bytes_total: usize,
    /// Whether the file ended with its footer and magic bytes: then nothing was lost.
    pub complete: bool,
    pub stopped_at: Option<String>,
}

/// Walks an MCAP file's records (the magic, then per record an opcode byte, a little-endian u64
/// length and the content): the offset where the last whole record ends (the file's length if
/// it is complete), and whether the file ends with a footer record followed by the magic bytes.
fn scan(buf: &[u8]) -> (usize, bool) {
    const FOOTER: u8 = 0x02;
    let m = mcap::MAGIC.len();
    let mut pos = m.min(buf.len());
    while pos + 9 <= buf.len() {
        let op = buf[pos];
        let mut len = [0u8; 8];
        len.copy_from_slice(&buf[pos + 1..pos + 9]);
        match (pos as u64 + 9).checked_add(u64::from_le_bytes(len)) {
            Some(end) if end <= buf.len() as u64 => pos = end as usize,
            _ => break,
        }
        if op == FOOTER {
            let complete = buf.len() == pos + m && buf[pos..] == *mcap::MAGIC;
            return (if complete { buf.len() } else { pos }, complete);
        }
    }
    (pos, false)
}

/// Copies every message of every complete chunk (and the metadata) of a possibly truncated file
/// `input` into a new, valid file `output`, and says truthfully whether anything was lost: the
/// messages of an unfinished chunk are compressed and cannot be counted, so the loss is reported
/// in bytes.
pub fn recover(input: &Path, output: &Path) -> Result<Recovery, DataError> {
    use mcap::read::{LinearReader, Options};
    let buf = std::fs::read(input).map_err(DataError::io(input))?;
    if !buf.starts_with(mcap::MAGIC) {
        return Err(DataError::Format(format!(
            "{} is not an MCAP file (no magic bytes at the start)",
            input.display()
        )));
    }
    let opts = enumset::EnumSet::only(Options::IgnoreEndMagic);
    let mut metadata = vec![];
    let mut stopped_at = None;
    for rec in LinearReader::new_with_options(&buf, opts)? {
        match rec {
            Ok(mcap::records::Record::Metadata(m)) => metadata.push(m),
            Ok(_) => {}
            Err(e) => {
                stopped_at = Some(e.to_string());
                break;
            }
        }
    }
    let mut messages = vec![];
    for m in super::read::messages(&buf, true) {
        match m {
            Ok(m) => messages.push(m),
            Err(e) => {
                stopped_at.get_or_insert(e.to_string());
                break;
            }
        }
    }
    let file = File::create(output).map_err(DataError::io(output))?;
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .profile("hgym")
        .create(BufWriter::new(file))?;
    for m in &metadata {
        w.write_metadata(m)?;
    }
    for m in &messages {
        w.write(m)?;
    }
    w.finish()?;
    let (bytes_read, complete) = scan(&buf);
    Ok(Recovery {
        messages: messages.len(),
        metadata: metadata.len(),
        bytes_read,
        bytes_total: buf.len(),
        complete: complete && stopped_at.is_none(),
        stopped_at,
    })
}
