"""Every command docs/python.md and README's Python section print runs, as printed: the Python
blocks as scripts, the bash lines with `floorcast` on PATH, in a temporary folder that mirrors
the repository (its buildings, maps, suites, examples, grids). Not run: `pip install` lines
(what CI itself runs to get here), and the Ray block, compiled only (CI does not install Ray).
"""

import os
import pathlib
import re
import subprocess
import sys

import pytest

from conftest import REPO, floorcast_bin

DOCS = [REPO / "docs" / "python.md", REPO / "README.md"]


def blocks(path):
    """`(language, code)` of the fenced blocks of a document; README: its Python section only."""
    text = path.read_text()
    if path.name == "README.md":
        start = text.index("## Python")
        text = text[start:text.index("\n## ", start + 1)]
    return re.findall(r"```(\w+)\n(.*?)```", text, flags=re.S)


@pytest.fixture(scope="module")
def mirror(tmp_path_factory):
    d = tmp_path_factory.mktemp("mirror")
    for name in ("buildings", "maps", "suites", "examples", "grids", "python"):
        (d / name).symlink_to(REPO / name)
    bin_dir = d / "bin"
    bin_dir.mkdir()
    (bin_dir / "floorcast").symlink_to(floorcast_bin())
    return d


CASES = [(p.name, i, lang, code) for p in DOCS for i, (lang, code) in enumerate(blocks(p))
         if lang in ("python", "bash")]


def test_the_documents_have_python_and_bash_blocks():
    langs = {(name, lang) for name, _, lang, _ in CASES}
    assert ("python.md", "python") in langs and ("python.md", "bash") in langs
    assert any(name == "README.md" for name, *_ in CASES)


@pytest.mark.parametrize("name,index,lang,code", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_a_printed_block_runs(mirror, name, index, lang, code):
    env = dict(os.environ, PATH=f"{mirror / 'bin'}{os.pathsep}{os.environ['PATH']}")
    if lang == "python":
        if "import ray" in code:
            compile(code, f"{name} block {index}", "exec")
            return
        script = mirror / f"block_{name}_{index}.py"
        script.write_text(code)
        p = subprocess.run([sys.executable, str(script)], cwd=mirror, env=env,
                           capture_output=True, text=True, timeout=900)
        assert p.returncode == 0, p.stderr
        return
    ran = 0
    for line in code.replace("\\\n", " ").splitlines():
        line = line.strip()
        if not line or line.startswith("#") or line.startswith("pip ") or line.startswith("pip install"):
            continue
        line = line.replace("python3 ", f"{sys.executable} ") if line.startswith("python3 ") else line
        p = subprocess.run(["bash", "-c", line], cwd=mirror, env=env, capture_output=True, text=True, timeout=900)
        assert p.returncode == 0, f"{line}\n{p.stderr}"
        ran += 1
    assert ran or "pip install" in code
