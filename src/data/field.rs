//! Flow-field snapshots in trajectory files: the `/field` channel, one message every k actions,
//! encoded as Foxglove's `foxglove.Grid` (JSON encoding, the cell data base64 little-endian
//! float32, fields interleaved per cell) so that Foxglove's 3D panel shows it as a coloured grid
//! and Python reads it with `numpy.frombuffer(base64.b64decode(m["data"]), "<f4")`. The chunk is
//! zstd-compressed like every other channel. hgym adds `episode`, `step`, `t` and `extent`
//! (x0, x1, y0, y1 in the env's units) to the Grid's fields.

use super::DataError;
use base64::Engine;
use serde_json::{json, Value};

/// `foxglove.NumericType.FLOAT32`.
const FLOAT32: u64 = 7;

/// JSON Schema of the message: foxglove.Grid plus hgym's episode, step, t and extent.
pub const SCHEMA: &str = r#"{"title":"foxglove.Grid","type":"object","properties":{
"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},
"frame_id":{"type":"string"},
"pose":{"type":"object","properties":{"position":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}},"orientation":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}}}},
"column_count":{"type":"integer"},
"cell_size":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"}}},
"row_stride":{"type":"integer"},"cell_stride":{"type":"integer"},
"fields":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"offset":{"type":"integer"},"type":{"type":"integer"}}}},
"data":{"type":"string","contentEncoding":"base64"},
"episode":{"type":"integer"},"step":{"type":"integer"},"t":{"type":"number"},
"extent":{"type":"array","items":{"type":"number"},"minItems":4,"maxItems":4}},
"required":["column_count","cell_stride","row_stride","fields","data","episode","step"]}"#;

/// Named scalar fields on one `nx x ny` grid, row-major `f[y * nx + x]`, `y` upwards.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    pub episode: u64,
    pub step: u64,
    pub t: f64,
    pub nx: usize,
    pub ny: usize,
    /// `[x0, x1, y0, y1]` of the grid in the env's units.
    pub extent: [f64; 4],
    pub fields: Vec<(String, Vec<f32>)>,
}

impl Snapshot {
    /// The `foxglove.Grid` JSON message.
    pub fn encode(&self) -> Result<Vec<u8>, DataError> {
        let cells = self.nx * self.ny;
        if let Some((name, f)) = self.fields.iter().find(|(_, f)| f.len() != cells) {
            return Err(DataError::Format(format!("field {name} has {} values, the grid {cells}", f.len())));
        }
        let k = self.fields.len();
        let mut data = Vec::with_capacity(cells * k * 4);
        for c in 0..cells {
            for (_, f) in &self.fields {
                data.extend_from_slice(&f[c].to_le_bytes());
            }
        }
        let [x0, x1, y0, y1] = self.extent;
        let v = json!({
            "timestamp": {"sec": self.t.max(0.0).floor() as u64, "nsec": (self.t.max(0.0).fract() * 1e9) as u64},
            "frame_id": "flow",
            "pose": {"position": {"x": x0, "y": y0, "z": 0.0}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
            "column_count": self.nx,
            "cell_size": {"x": (x1 - x0) / self.nx as f64, "y": (y1 - y0) / self.ny as f64},
            "row_stride": self.nx * k * 4,
            "cell_stride": k * 4,
            "fields": self.fields.iter().enumerate()
                .map(|(j, (name, _))| json!({"name": name, "offset": 4 * j, "type": FLOAT32}))
                .collect::<Vec<_>>(),
            "data": base64::engine::general_purpose::STANDARD.encode(&data),
            "episode": self.episode,
            "step": self.step,
            "t": self.t,
            "extent": self.extent,
        });
        Ok(serde_json::to_vec(&v)?)
    }

    /// The inverse of [`Snapshot::encode`].
    pub fn decode(bytes: &[u8]) -> Result<Snapshot, DataError> {
        let bad = |what: String| DataError::Format(format!("field message: {what}"));
        let v: Value = serde_json::from_slice(bytes).map_err(|e| bad(e.to_string()))?;
        let int = |k: &str| v[k].as_u64().ok_or_else(|| bad(format!("no integer {k}")));
        let nx = int("column_count")? as usize;
        let stride = int("cell_stride")? as usize;
        let text = v["data"].as_str().ok_or_else(|| bad("no data".into()))?;
        let data = base64::engine::general_purpose::STANDARD
            .decode(text)
            .map_err(|e| bad(format!("data: {e}")))?;
        let row = nx.checked_mul(stride).filter(|&r| r > 0);
        let Some(row) = row.filter(|r| data.len().is_multiple_of(*r)) else {
            return Err(bad("data does not fill whole rows".into()));
        };
        let ny = data.len() / row;
        let listed = v["fields"].as_array().ok_or_else(|| bad("no fields list".into()))?;
        if listed.len() > stride / 4 {
            return Err(bad(format!("{} fields cannot fit a {stride}-byte cell", listed.len())));
        }
        let mut fields = vec![];
        for f in listed {
            let name = f["name"].as_str().ok_or_else(|| bad("a field without a name".into()))?;
            let off = f["offset"].as_u64().ok_or_else(|| bad(format!("field {name} without an offset")))? as usize;
            if off.checked_add(4).is_none_or(|end| end > stride) {
                return Err(bad(format!("field {name} at offset {off} does not fit a {stride}-byte cell")));
            }
            let vals = (0..nx * ny)
                .map(|c| {
                    let b = &data[c * stride + off..c * stride + off + 4];
                    f32::from_le_bytes([b[0], b[1], b[2], b[3]])
                })
                .collect();
            fields.push((name.to_string(), vals));
        }
        let extent = v["extent"]
            .as_array()
            .filter(|e| e.len() == 4)
            .and_then(|e| e.iter().map(|x| x.as_f64()).collect::<Option<Vec<f64>>>())
            .ok_or_else(|| bad("extent is not four numbers".into()))?;
        Ok(Snapshot {
            episode: int("episode")?,
            step: int("step")?,
            t: v["t"].as_f64().ok_or_else(|| bad("no time t".into()))?,
            nx,
            ny,
            extent: [extent[0], extent[1], extent[2], extent[3]],
            fields,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_round_trip() {
        let s = Snapshot {
            episode: 2,
            step: 30,
            t: 12.5,
            nx: 3,
            ny: 2,
            extent: [0.0, 3.0, -1.0, 1.0],
            fields: vec![
                ("u".into(), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
                ("vorticity".into(), vec![f32::NAN, -1.0, 0.5, 0.25, 1e-8, 7.0]),
            ],
        };
        let back = Snapshot::decode(&s.encode().unwrap()).unwrap();
        assert_eq!(back.nx, 3);
        assert_eq!(back.ny, 2);
        assert_eq!(back.fields[0], s.fields[0]);
        assert!(back.fields[1].1[0].is_nan());
        assert_eq!(back.fields[1].1[1..], s.fields[1].1[1..]);
        assert_eq!(back.extent, s.extent);
    }

    #[test]
    fn wrong_field_length_is_refused() {
        let s = Snapshot {
            episode: 0,
            step: 0,
            t: 0.0,
            nx: 2,
            ny: 2,
            extent: [0.0; 4],
            fields: vec![("u".into(), vec![0.0; 3])],
        };
        assert!(s.encode().unwrap_err().to_string().contains("has 3 values"));
    }
}
