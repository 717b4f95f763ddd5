#!/usr/bin/env python3
"""Which committed results are older than the code they were made with.

Every result hgym writes carries a manifest with the commit its binary was built from
(`manifest.git_commit`). A result is older than its code when commits since that one touched the
code that made it: the solvers and the flow layer for a validation report; those plus the
environments and the learners for training, evaluation, transfer and runs. `make nightly` prints
this table in results/nightly/summary.md and leaves the long results themselves alone; re-run one
with the command in its manifest (or the leaderboard's `reproduce`) to refresh it.

Usage: scripts/results_age.py [RESULTS_DIR]   (default: results; results/nightly is skipped,
nightly refreshes it). Prints a Markdown section; exit 0.
"""

import json
import subprocess
import sys
from pathlib import Path

# What made each kind of result, as paths in the repository.
VALIDATION_CODE = ["solvers", "src/flow", "src/validate"]
LEARNING_CODE = ["solvers", "src/flow", "src/env", "agents", "src/train", "src/transfer"]


def git(*args: str) -> str | None:
    out = subprocess.run(["git", *args], capture_output=True, text=True)
    return out.stdout.strip() if out.returncode == 0 else None


def commit_of(path: Path) -> str | None:
    """The commit in the manifest of the JSON file `path`, if it has one."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    manifest = data.get("manifest") if isinstance(data, dict) else None
    commit = manifest.get("git_commit") if isinstance(manifest, dict) else None
    return commit if isinstance(commit, str) and commit else None


def results(root: Path):
    """(result, commit, code paths): a run folder (one with a `manifest.json`) for the files in
    it, else the JSON file."""
    for path in sorted(root.rglob("*.json")):
        rel = path.relative_to(root)
        if rel.parts[0] == "nightly":
            continue
        commit = commit_of(path)
        if commit is None:
            continue
        code = VALIDATION_CODE if rel.parts[0] == "validation" else LEARNING_CODE
        yield (path.parent if (path.parent / "manifest.json").exists() else path), commit, code


def main() -> int:
    root = Path(sys.argv[1] if len(sys.argv) > 1 else "results")
    rows, current, unknown, seen = [], 0, [], set()
    age: dict[tuple[str, tuple[str, ...]], int | None] = {}
    for result, commit, code in results(root):
        if result in seen:
            continue
        seen.add(result)
        # A binary built from a tree with uncommitted changes says `<commit>-dirty`: aged from
        # the commit it started from.
        base = commit.removesuffix("-dirty")
        key = (base, tuple(code))
        if key not in age:
            count = git("rev-list", "--count", f"{base}..HEAD", "--", *code)
            age[key] = int(count) if count is not None else None
        n = age[key]
        if n is None:
            unknown.append((result, commit))
        elif n == 0:
            current += 1
        else:
            date = git("log", "-1", "--format=%cs", base) or "?"
            rows.append((n, str(result), commit, date, code))
    print("## results older than the code they were made with")
    print()
    print(f"{current} of {len(seen)} results were made with their code as it is now; "
          f"{len(rows)} are older (commits since theirs that touch their code), "
          f"{len(unknown)} name a commit this clone does not have.")
    if rows:
        print()
        print("| result | made with | commits to its code since | code |")
        print("|---|---|---|---|")
        for n, result, commit, date, code in sorted(rows, key=lambda r: (-r[0], r[1])):
            print(f"| {result} | {commit} ({date}) | {n} | {' '.join(code)} |")
    for result, commit in unknown:
        print(f"- {result}: commit {commit} is not in this clone's history")
    return 0


if __name__ == "__main__":
    sys.exit(main())
