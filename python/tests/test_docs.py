"""Every command docs/python.md, README's Python section and examples/python/README.md print
runs, as printed: the Python blocks as scripts, the shell lines with `floorcast` on PATH, in a
temporary folder that mirrors the repository (its buildings, maps, suites, examples, grids).
Not run: `pip install` lines (what CI itself runs to get here); the Ray block, compiled only
(CI does not install Ray); and the lines of `NOT_RUN`, each checked otherwise.
"""

import os
import pathlib
import re
import subprocess
import sys

import pytest

from conftest import REPO, floorcast_bin

DOCS = [REPO / "docs" / "python.md", REPO / "README.md", REPO / "examples" / "python" / "README.md"]

#: Printed commands not run here, and how each is checked instead.
NOT_RUN = {
    # 8 minutes on 2 cores: the same code runs with --quick (printed too, and run), and
    # test_example.py checks the committed policy.
    "python3 examples/python/train.py",
    # 9 minutes: test_example.py checks its plan (the test split, its strategies and test).
    "floorcast run examples/python/grid.toml",
    # The report of that grid's results (the example's README quotes it).
    "floorcast report results/python-policy --reference random-frontier",
    # The leaderboard's commands: tests/board_cli.rs runs them (with the committed runs).
    "floorcast run grids/leaderboard.toml --import results/reference/leaderboard/runs.jsonl.gz",
    "floorcast report results/leaderboard --reference nearest",
}


def blocks(path):
    """`(language, code)` of the fenced blocks of a document; README: its Python section only."""
    text = path.read_text()
    if path == REPO / "README.md":
        start = text.index("## Python")
        text = text[start:text.index("\n## ", start + 1)]
    return re.findall(r"```(\w+)\n(.*?)```", text, flags=re.S)


def strip_comment(line):
    """The command without its trailing `# comment`."""
    return re.sub(r"\s+#.*$", "", line).strip()


@pytest.fixture(scope="module")
def mirror(tmp_path_factory):
    d = tmp_path_factory.mktemp("mirror")
    for name in ("buildings", "maps", "suites", "examples", "grids", "python"):
        (d / name).symlink_to(REPO / name)
    bin_dir = d / "bin"
    bin_dir.mkdir()
    (bin_dir / "floorcast").symlink_to(floorcast_bin())
    return d


CASES = [(str(p.relative_to(REPO)), i, lang, code) for p in DOCS for i, (lang, code) in enumerate(blocks(p))
         if lang in ("python", "bash") or (lang == "sh" and p.parent.name == "python")]


def test_the_documents_have_python_and_bash_blocks():
    langs = {(name, lang) for name, _, lang, _ in CASES}
    assert ("docs/python.md", "python") in langs and ("docs/python.md", "bash") in langs
    assert ("README.md", "python") in langs and ("examples/python/README.md", "sh") in langs


@pytest.mark.parametrize("name,index,lang,code", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_a_printed_block_runs(mirror, name, index, lang, code):
    env = dict(os.environ, PATH=f"{mirror / 'bin'}{os.pathsep}{os.environ['PATH']}")
    if lang == "python":
        if "import ray" in code:
            compile(code, f"{name} block {index}", "exec")
            return
        script = mirror / f"block_{name.replace('/', '_')}_{index}.py"
        script.write_text(code)
        p = subprocess.run([sys.executable, str(script)], cwd=mirror, env=env,
                           capture_output=True, text=True, timeout=900)
        assert p.returncode == 0, p.stderr
        return
    ran = 0
    for line in code.replace("\\\n", " ").splitlines():
        line = strip_comment(line.strip())
        if not line or line.startswith("#") or line.startswith("pip ") or line in NOT_RUN:
            continue
        line = line.replace("python3 ", f"{sys.executable} ") if line.startswith("python3 ") else line
        p = subprocess.run(["bash", "-c", line], cwd=mirror, env=env, capture_output=True, text=True, timeout=900)
        assert p.returncode == 0, f"{line}\n{p.stderr}"
        ran += 1
    assert ran or "pip install" in code or any(n in code for n in NOT_RUN)


def test_every_command_not_run_is_still_printed():
    printed = {strip_comment(l.strip()) for p in DOCS for _, code in blocks(p) for l in code.splitlines()}
    assert NOT_RUN <= printed, NOT_RUN - printed
