"""Loads an `hgym export --to hf` folder the way users will: the card's YAML front matter,
every config with `datasets.load_dataset(folder, config)` (offline) and with pandas, and
compares it with the MCAP files it came from (read with the Python `mcap` reader). Prints a
JSON summary for tests/hf_export.rs."""
import base64
import json
import os
import sys

import numpy as np
import pandas as pd
import yaml
from mcap.reader import make_reader

folder, runs = sys.argv[1], sys.argv[2]
os.environ["HF_DATASETS_OFFLINE"] = "1"
import datasets  # noqa: E402  (after the offline switch)

card = open(os.path.join(folder, "README.md")).read()
front = yaml.safe_load(card.split("---")[1])
out = {"card": {k: front.get(k) for k in ("license", "task_categories", "size_categories", "tags")},
       "configs": {}}

# The MCAP side: per (run, episode, step) the reward and obs; per snapshot the vorticity.
mcap_rows, mcap_fields, grid_schemas = {}, {}, set()
for root, _, files in os.walk(runs):
    for name in files:
        if not name.endswith(".mcap"):
            continue
        run = os.path.relpath(root, runs)
        with open(os.path.join(root, name), "rb") as f:
            for schema, channel, message in make_reader(f).iter_messages():
                body = json.loads(message.data)
                key = (run, body["episode"], body["step"])
                if channel.topic == "/reward":
                    mcap_rows.setdefault(key, {})["reward"] = body["reward"]
                elif channel.topic == "/obs":
                    mcap_rows.setdefault(key, {})["obs"] = body["obs"]
                elif channel.topic == "/field":
                    grid_schemas.add(schema.name)
                    raw = np.frombuffer(base64.b64decode(body["data"]), "<f4")
                    k = body["cell_stride"] // 4
                    names = [fl["name"] for fl in body["fields"]]
                    mcap_fields[key] = raw.reshape(-1, k)[:, names.index("vorticity")]
out["grid_schemas"] = sorted(grid_schemas)

for cfg in front["configs"]:
    name = cfg["config_name"]
    ds = datasets.load_dataset(folder, name, split="train")
    df = pd.read_parquet(os.path.join(folder, os.path.dirname(cfg["data_files"][0]["path"])))
    info = {"rows": len(ds), "pandas_rows": len(df), "columns": ds.column_names,
            "shards": len([p for p in os.listdir(os.path.join(folder, os.path.dirname(cfg["data_files"][0]["path"])))])}
    if name.endswith("-fields"):
        worst = 0.0
        for r in ds:
            w = np.asarray(r["vorticity"], dtype=np.float32)
            m = mcap_fields[(r["run"], r["episode"], r["step"])]
            same = (w == m) | (np.isnan(w) & np.isnan(m))
            worst = max(worst, float((~same).sum()))
            assert len(w) == r["nx"] * r["ny"]
        info["field_mismatches"] = worst
        info["nx"] = int(df["nx"].iloc[0])
        info["nan_cells"] = int(np.isnan(np.asarray(ds[0]["vorticity"], dtype=np.float32)).sum())
    else:
        mismatches = 0
        for r in ds:
            m = mcap_rows[(r["run"], r["episode"], r["step"])]
            if r["obs"] != m["obs"] or r["reward"] != m.get("reward"):
                mismatches += 1
        info["mismatches"] = mismatches
        info["reward_sum"] = float(df["reward"].sum())
        info["null_actions"] = int(df["action"].isna().sum())
        info["episodes"] = int(df.groupby("run")["episode"].nunique().sum())
        info["dtypes"] = {c: str(t) for c, t in df.dtypes.items()}
    out["configs"][name] = info
print(json.dumps(out))
