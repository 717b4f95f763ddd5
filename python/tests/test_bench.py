"""`hgym bench python` (the boundary's overhead and the vector env's throughput) runs against
this interpreter's package and reports every row; the targets are judged by the full run
(`hgym bench python`), not by this quick one."""

import json
import os
import subprocess
import sys

from test_gymnasium import hgym_binary


def test_bench_python_quick_reports_every_row():
    out = subprocess.run(
        [hgym_binary(), "bench", "python", "--quick", "--json"],
        capture_output=True, text=True, env={**os.environ, "HGYM_PYTHON": sys.executable}, timeout=600,
    )
    assert out.returncode == 0, out.stderr
    b = json.loads(out.stdout)
    assert b["about"]["hgym"] and b["peer"] is None
    assert sorted((r["case"]["id"], r["threads"]) for r in b["boundary"]) == [
        ("Cylinder_2D_Re100", 1), ("Cylinder_2D_Re100", 2), ("Kolmogorov_2D_Re40", 1), ("Kolmogorov_2D_Re40", 2)]
    for r in b["boundary"]:
        assert 0 < r["pairs"]["median_ours"] and 0 < r["pairs"]["median_peer"]
        assert len(r["overhead_us"]) == 2
    assert [v["threads"] for v in b["vector"]] == [1, 2]
    for v in b["vector"]:
        assert v["num_envs"] == 4 and 0 < v["pairs"]["median_speedup"] < 2
