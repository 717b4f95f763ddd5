"""Reads an hgym trajectory with the Python `mcap` reader (the tool people use) and prints a
JSON summary: message counts per topic, episodes, schema encodings, manifest keys."""
import json
import sys
from collections import Counter

from mcap.reader import make_reader

path = sys.argv[1]
with open(path, "rb") as f:
    reader = make_reader(f)
    counts = Counter()
    episodes = set()
    encodings = {}
    steps = Counter()
    for schema, channel, message in reader.iter_messages():
        body = json.loads(message.data)
        counts[channel.topic] += 1
        episodes.add(body["episode"])
        encodings[channel.topic] = [schema.encoding, channel.message_encoding]
        if channel.topic == "/reward":
            steps[body["episode"]] += 1
    manifest = {}
    for m in reader.iter_metadata():
        if m.name == "manifest":
            manifest = dict(m.metadata)
print(json.dumps({
    "counts": counts,
    "episodes": sorted(episodes),
    "steps_per_episode": {str(k): v for k, v in sorted(steps.items())},
    "encodings": encodings,
    "manifest_keys": sorted(manifest),
    "env_id": manifest.get("env_id"),
}))
