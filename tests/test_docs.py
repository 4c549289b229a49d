"""The documentation: it builds with warnings as errors, its docstring examples pass as doctests, and every
command the tutorials show runs as written on the sample heads (issue #36)."""
import os
import re
import shlex
import subprocess
import sys

import pytest

from shared_data import ROOT

DOCS = ROOT / "docs"
PAGES = [DOCS / "getting-started.md"] + sorted((DOCS / "tutorials").glob("*.md"))


def _sphinx(builder, out):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", builder, str(DOCS),
                           str(out)], env=env, capture_output=True, text=True, timeout=600)


def test_the_site_builds_with_warnings_as_errors(tmp_path):
    r = _sphinx("html", tmp_path / "html")
    # docutils reports a docstring's markup errors on stderr without failing the build: they count too
    problems = [line for line in r.stderr.splitlines() if re.search(r"ERROR|WARNING|Warning", line)]
    assert r.returncode == 0 and not problems, r.stderr[-3000:]
    for page in ("index", "getting-started", "reference/cli", "reference/api", "accuracy", "changelog",
                 *(f"tutorials/{p.stem}" for p in PAGES[1:])):
        assert (tmp_path / "html" / f"{page}.html").is_file(), page
    cli = (tmp_path / "html" / "reference" / "cli.html").read_text()
    sys.path.insert(0, str(ROOT))
    from cli.commands import COMMANDS

    assert all(f"autobones {c}" in cli for c in COMMANDS)  # generated from the parser: every command
    accuracy = (tmp_path / "html" / "accuracy.html").read_text()
    assert accuracy.count("<table") >= 10  # the benchmark tables came in by include


@pytest.mark.slow  # over 20 s (measured); `-m "not slow"` leaves it out
def test_the_docstring_examples_pass_as_doctests(tmp_path):
    r = _sphinx("doctest", tmp_path / "doctest")
    report = (tmp_path / "doctest" / "output.txt").read_text()
    assert r.returncode == 0 and "0 failures in tests" in report, report[-3000:]
    ran = int(re.search(r"(\d+) tests\n", report)[1])
    assert ran >= 40, report  # place, transfer, transfer_attributes, detect_landmarks, load_rig, Rig.pose, samples


def _commands(page):
    """The ``$ `` lines of a page's ``console`` blocks, in order."""
    out, inside = [], False
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            inside = line.strip() == "```console"
        elif inside and line.startswith("$ "):
            out.append(line[2:])
    return out


def test_every_tutorial_shows_commands_and_starts_with_the_samples():
    for page in PAGES:
        if page.name != "index.md":
            cmds = _commands(page)
            assert cmds and cmds[0] == "autobones samples s/", page.name


def _view(cmd, cwd):
    """``autobones view`` (and ``landmarks --edit``) serve until stopped: run without a browser, read the
    address, stop it (an editor stopped so has saved nothing)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.Popen([sys.executable, "-m", "cli.main", *shlex.split(cmd)[1:], "--no-browser"], cwd=cwd, env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = p.stdout.readline()
    finally:
        p.terminate()
        p.wait(10)
    assert url.startswith("http://127.0.0.1:"), (cmd, url, p.stderr.read())


@pytest.mark.slow  # over 20 s (measured); `-m "not slow"` leaves it out
@pytest.mark.parametrize("page", [p for p in PAGES if p.name != "index.md"], ids=lambda p: p.stem)
def test_every_tutorial_command_runs_as_written(tmp_path, monkeypatch, capsys, page):
    """Each page on a fresh folder; ``autobones`` lines run in this process (the same ``main`` the console
    script calls: a second of interpreter start saved per line), shell lines (mkdir, cp) in bash."""
    sys.path.insert(0, str(ROOT))
    from cli.main import main

    monkeypatch.chdir(tmp_path)
    for cmd in _commands(page):
        if cmd.startswith("autobones view") or " --edit" in cmd:  # both serve a page until stopped
            _view(cmd, tmp_path)
            continue
        if cmd.startswith("autobones "):
            code = main(shlex.split(cmd)[1:])
            cap = capsys.readouterr()
            assert code == 0, f"{page.name}: {cmd}\n{cap.err[-2000:]}"
            assert cap.out.strip(), f"{page.name}: {cmd} printed no result line"
        else:
            r = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, timeout=60)
            assert r.returncode == 0, f"{page.name}: {cmd}\n{r.stderr}"
        for out in re.findall(r"-o (\S+)", cmd):  # what the page says is written, is
            assert (tmp_path / out).exists(), f"{page.name}: {cmd} did not write {out}"


def test_the_gallery_without_the_shared_data_says_so_in_one_line_and_writes_nothing(tmp_path):
    """A fresh clone has no ../shared/data: one line naming it, exit 2, no picture touched."""
    import shutil

    repo = tmp_path / "clone"
    shutil.copytree(ROOT / "gallery", repo / "gallery")
    before = {p.name: p.read_bytes() for p in (repo / "gallery").glob("*.png")}
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "gallery/make_gallery.py"], cwd=repo, env=env, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and r.stdout == "" and r.stderr.count("\n") == 1, r.stderr
    assert "needs the shared data set" in r.stderr and str(tmp_path / "shared" / "data") in r.stderr
    assert {p.name: p.read_bytes() for p in (repo / "gallery").glob("*.png")} == before
    assert not any(n.startswith(".gallery-") for n in os.listdir(repo / "gallery"))  # no staging folder left
