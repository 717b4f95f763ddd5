//! MCAP trajectories. Four JSON-encoded channels, each with a declared JSON Schema:
//! `/obs` (`episode`, `step`, `obs`), `/action` (`normalised`, `physical`), `/reward`
//! (`reward`, `terminated`, `truncated`) and `/info` (every numeric and text info value); step 0
//! of each episode is the reset's observation. A metadata record `manifest` holds the env spec,
//! its hash, seeds, policy and code version. Chunks are zstd-compressed and closed at the end
//! of every episode, so a killed writer loses at most the episode in progress (`recover`
//! salvages every complete chunk); `finish` writes the summary and index.
//! Log times are simulated time: the file's global step count times the control interval.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use hgym_agents::{Info, StepResult};
use mcap::records::{MessageHeader, Metadata};
use mcap::write::Writer;
use serde_json::json;

fn err(e: impl std::fmt::Display) -> String {
    format!("MCAP: {e}")
}

const OBS_SCHEMA: &str = r#"{"type":"object","properties":{"episode":{"type":"integer"},"step":{"type":"integer"},"obs":{"type":"array","items":{"type":"number"}}},"required":["episode","step","obs"]}"#;
const ACTION_SCHEMA: &str = r#"{"type":"object","properties":{"episode":{"type":"integer"},"step":{"type":"integer"},"normalised":{"type":"array","items":{"type":"number"}},"physical":{"type":"array","items":{"type":"number"}}},"required":["episode","step","normalised","physical"]}"#;
const REWARD_SCHEMA: &str = r#"{"type":"object","properties":{"episode":{"type":"integer"},"step":{"type":"integer"},"reward":{"type":"number"},"terminated":{"type":"boolean"},"truncated":{"type":"boolean"}},"required":["episode","step","reward","terminated","truncated"]}"#;
const INFO_SCHEMA: &str = r#"{"type":"object","properties":{"episode":{"type":"integer"},"step":{"type":"integer"},"values":{"type":"object","additionalProperties":{"type":["number","null"]}},"text":{"type":"object","additionalProperties":{"type":"string"}}},"required":["episode","step","values","text"]}"#;

pub struct TrajectoryWriter {
    writer: Option<Writer<BufWriter<File>>>,
    channels: [u16; 4],
    interval_ns: f64,
    global_step: u64,
    episode: u64,
    step: u64,
    sequence: u32,
}

impl TrajectoryWriter {
    /// Creates `path` with the manifest (string key-values) as metadata.
    pub fn create(path: &Path, control_interval: f64, manifest: BTreeMap<String, String>) -> Result<Self, String> {
        let file = File::create(path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
        let mut w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("hgym")
            .library(format!("hgym {}", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))
            .map_err(err)?;
        let mut channels = [0u16; 4];
        for (k, (topic, schema)) in [
            ("/obs", OBS_SCHEMA),
            ("/action", ACTION_SCHEMA),
            ("/reward", REWARD_SCHEMA),
            ("/info", INFO_SCHEMA),
        ]
        .into_iter()
        .enumerate()
        {
            let name = format!("hgym{}", topic.replace('/', "."));
            let sid = w.add_schema(&name, "jsonschema", schema.as_bytes()).map_err(err)?;
            channels[k] = w.add_channel(sid, topic, "json", &BTreeMap::new()).map_err(err)?;
        }
        w.write_metadata(&Metadata {
            name: "manifest".into(),
            metadata: manifest,
        })
        .map_err(err)?;
        Ok(TrajectoryWriter {
            writer: Some(w),
            channels,
            interval_ns: control_interval * 1e9,
            global_step: 0,
            episode: 0,
            step: 0,
            sequence: 0,
        })
    }

    fn put(&mut self, channel: usize, value: serde_json::Value) -> Result<(), String> {
        let log_time = (self.global_step as f64 * self.interval_ns) as u64;
        self.sequence += 1;
        let data = serde_json::to_vec(&value).map_err(err)?;
        let w = self.writer.as_mut().ok_or("MCAP: writer already finished")?;
        w.write_to_known_channel(
            &MessageHeader {
                channel_id: self.channels[channel],
                sequence: self.sequence,
                log_time,
                publish_time: log_time,
            },
            &data,
        )
        .map_err(err)
    }

    fn info_json(&self, info: &Info) -> serde_json::Value {
        json!({"episode": self.episode, "step": self.step, "values": info.values, "text": info.text})
    }

    /// Step 0 of a new episode: the reset's observation and info.
    pub fn reset(&mut self, obs: &[f64], info: &Info) -> Result<(), String> {
        self.step = 0;
        self.put(0, json!({"episode": self.episode, "step": 0, "obs": obs}))?;
        let v = self.info_json(info);
        self.put(3, v)
    }

    /// One step: the action taken (normalised; physical values from info `actuation_k`) and
    /// what it returned. Closes the chunk at the episode's end.
    pub fn step(&mut self, action: &[f64], r: &StepResult) -> Result<(), String> {
        self.step += 1;
        self.global_step += 1;
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
        if r.terminated || r.truncated {
            self.end_episode()?;
        }
        Ok(())
    }

    /// Closes the current chunk (everything so far survives a kill) and starts a new episode.
    pub fn end_episode(&mut self) -> Result<(), String> {
        self.episode += 1;
        self.global_step += 1;
        self.writer.as_mut().ok_or("MCAP: writer already finished")?.flush().map_err(err)
    }

    /// Writes the summary and index; the file is complete.
    pub fn finish(&mut self) -> Result<(), String> {
        if let Some(mut w) = self.writer.take() {
            w.finish().map_err(err)?;
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
    pub bytes_read: usize,
    pub bytes_total: usize,
    pub stopped_at: Option<String>,
}

/// Copies every message of every complete chunk (and the metadata) of a possibly truncated file
/// `input` into a new, valid file `output`.
pub fn recover(input: &Path, output: &Path) -> Result<Recovery, String> {
    use mcap::read::{LinearReader, MessageStream, Options};
    let buf = std::fs::read(input).map_err(|e| format!("cannot read {}: {e}", input.display()))?;
    if !buf.starts_with(mcap::MAGIC) {
        return Err(format!("{} is not an MCAP file (no magic bytes at the start)", input.display()));
    }
    let opts = enumset::EnumSet::only(Options::IgnoreEndMagic);
    let mut metadata = vec![];
    let mut stopped_at = None;
    for rec in LinearReader::new_with_options(&buf, opts).map_err(err)? {
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
    for m in MessageStream::new_with_options(&buf, opts).map_err(err)? {
        match m {
            Ok(m) => messages.push(m),
            Err(e) => {
                stopped_at.get_or_insert(e.to_string());
                break;
            }
        }
    }
    let file = File::create(output).map_err(|e| format!("cannot create {}: {e}", output.display()))?;
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .profile("hgym")
        .create(BufWriter::new(file))
        .map_err(err)?;
    for m in &metadata {
        w.write_metadata(m).map_err(err)?;
    }
    for m in &messages {
        w.write(m).map_err(err)?;
    }
    w.finish().map_err(err)?;
    Ok(Recovery {
        messages: messages.len(),
        metadata: metadata.len(),
        bytes_read: buf.len(),
        bytes_total: buf.len(),
        stopped_at,
    })
}
