"""`scripts/results_age.py` (in `make nightly`'s summary): a result is older than its code when
commits since the one in its manifest touch the code that made it, and only then."""

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "results_age.py"


def git(repo: Path, *args: str) -> str:
    return subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True, text=True).stdout.strip()


def commit_all(repo: Path, message: str) -> str:
    git(repo, "add", "-A")
    git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", message)
    return git(repo, "rev-parse", "--short=12", "HEAD")


def write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def age(repo: Path) -> str:
    out = subprocess.run([sys.executable, str(SCRIPT), "results"], cwd=repo, check=True, capture_output=True, text=True)
    return out.stdout


def test_results_age_with_the_code_that_made_them(tmp_path):
    repo = tmp_path
    git(repo, "init", "-q")
    write(repo / "solvers" / "lbm.rs", "1")
    write(repo / "agents" / "td3.rs", "1")
    made = commit_all(repo, "code")
    manifest = lambda commit: json.dumps({"manifest": {"git_commit": commit}})
    write(repo / "results" / "validation" / "cylinder.json", manifest(made))
    write(repo / "results" / "validation" / "sphere.json", manifest(made + "-dirty"))
    write(repo / "results" / "train" / "run" / "seed0" / "manifest.json", manifest(made))
    write(repo / "results" / "train" / "run" / "seed0" / "eval.json", manifest(made))
    write(repo / "results" / "nightly" / "train" / "x" / "manifest.json", manifest("0000000"))
    commit_all(repo, "results")
    assert "3 of 3 results were made with their code as it is now; 0 are older" in age(repo)

    # A learner changes: the training run is older, the validation reports are not.
    write(repo / "agents" / "td3.rs", "2")
    commit_all(repo, "learner")
    out = age(repo)
    assert "2 of 3 results were made with their code as it is now; 1 are older" in out
    assert f"| results/train/run/seed0 | {made} (" in out and "| 1 |" in out

    # A solver changes: all three are older, the training run by two commits.
    write(repo / "solvers" / "lbm.rs", "2")
    commit_all(repo, "solver")
    out = age(repo)
    assert "0 of 3 results were made with their code as it is now; 3 are older" in out
    assert f"| results/train/run/seed0 | {made} (" in out and "| 2 |" in out
    assert f"| results/validation/sphere.json | {made}-dirty (" in out
