"""Every shell example in README.md and docs/*.md runs; every YAML example loads through its config loader.

Python examples (```python blocks) run too, each as one script in the document's directory, in document order
with the commands (a script may read what a command above wrote); listed in ``DECISIONS`` as ``python: <first
line>``. Command blocks are the fenced blocks tagged ``bash``, ``sh``, ``shell``, ``console`` (``$ `` lines are
commands, the lines after one its documented output) and ``crontab`` (the command after the five time fields).
An untagged block that starts like a command (``fivid ``, ``$ ``, ``python ``) is an error: tag it, or tag it
``text`` when it is a synopsis. A document's commands run in order, in one temporary directory per document
(so a command can use what an earlier one wrote), with ``configs/``, ``pipelines/`` and ``sample_data/``
linked in, through bash with ``fivid`` defined as ``python -m fivid`` on this tree (PYTHONPATH); each must
exit 0, or the code listed in ``EXIT_CODES`` (a documented failure); a console command's output must match
the documented one (doctest rules: ``...`` and ``…`` match anything, whitespace is normalised).

By default a command runs in the fast test. ``DECISIONS`` lists every other one, keyed by the command as
written (comments dropped, whitespace collapsed), with the reason:

- ``slow(reason, quick=..., run=...)``: long (a full study, the full pipeline, a long simulation): it runs in
  ``test_documented_commands_slow`` (``-m slow``), as written or, for a study of 15-25 min, as ``run`` (its
  ``--quick`` variant); ``quick``, when given, is the documented quick substitution the fast test runs.
- ``skip(reason)``: cannot run here (network, root, apt, a cluster, cron), needs what a skipped or Python
  example makes, or is a 20-min study whose ``--quick`` line beside it runs; never executed.

``test_decisions_match_the_docs`` asserts that every listed command is in the docs, so the skipped list is
exactly what the docs hold: a new block is executed unless somebody lists it here with a reason.

``SETUP`` gives, per document, the files its examples assume the reader has (made by the commands it names
or by tests/helpers/daq_writers.py); ``docs/surface.md`` uses the real Dektak trace in ``../shared/real_data``.

YAML blocks (``yaml``/``yml``) are loaded by the loader of their kind, found by their keys:
``fivid-rig-profile`` -> ``fivid.io.rig_profile.rig_profile_from_mapping``; ``fivid-study`` ->
``fivid.study.config.load_study``; ``fivid-run`` -> ``fivid.pipeline.config.load_run_config``;
top-level keys of a model config (``bodies``, ``damping``, ``contacts``, ...) -> merged into a shipped model
(``FRAGMENT_BASES``) and built by ``fivid.fe.build.build_model``; a fragment of a smaller part (an edge
selector, a body's ``grading``, a contact's ``rigid`` master) is placed into the base at the path
``FRAGMENT_PLACES`` names. A block with alternatives separated by a ``# or`` line is checked per alternative.
"""

from __future__ import annotations

import doctest
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
REAL_DATA = ROOT.parent / "shared" / "real_data"
DOCS = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
COMMAND_LANGS = {"bash", "sh", "shell", "console", "crontab"}
YAML_LANGS = {"yaml", "yml"}
#: copied into each document's temp dir (small; a documented command may rewrite a file there, e.g. the convergence
#: table, and must not rewrite the repository's) and linked (large, only read)
COPIED = ("configs", "pipelines")
LINKED = ("sample_data",)


# ------------------------------------------------------------------------------------------------ decisions

@dataclass(frozen=True)
class Decision:
    """What the fast and the slow test run for a documented command (None: nothing) and why."""

    fast: str | None
    slow: str | None
    reason: str


def skip(reason: str) -> Decision:
    return Decision(None, None, reason)


def slow(reason: str, quick: str | None = None, run: str = "") -> Decision:
    """Run as written (or ``run``) in the slow test only; ``quick`` in the fast one."""
    return Decision(quick, run, reason)  # "" = the command as written


_PIPELINE = "fivid run pipelines/calibration.yaml --config configs/runs/sample.yaml"
_SIM = ('fivid simulate configs/models/triboair.yaml --mu 0.3 --velocity "10 mm/s" --load "5 N" '
        '--duration "0.1 s" --sample-rate "51.2 kHz" -o sim.nc')
_SIM_LAW = ('fivid simulate configs/models/triboair.yaml --law law.nc --roughness "1.6 um" --seed 3 '
            '--velocity "10 mm/s" --load "5 N" --duration "0.1 s" --sample-rate "51.2 kHz" -o sim-law.nc')
_QUICK_SIM = ('the 1 mm rig for 0.1 s is minutes of solver time (docs/solver.md: ~194 s projected); the fast '
              'test runs the 2 mm variant triboair_coarse.yaml for 5 ms')

DECISIONS: dict[str, Decision] = {
    # README.md and docs/verification.md (fivid verify, issue 28)
    "fivid verify --quick -o verification": slow(
        "every case at --quick resolution: ~20 s of compute plus the dask start-up, a minute on a loaded machine "
        "(CI also runs it as a step of its own); the fast test runs two of its cases in-process",
        quick="fivid verify --quick --case welch_parseval --case hoffmann_threshold --workers 0 -o verification"),
    "fivid verify -o verification": slow("the full manual: every case at full resolution, 1-2 min on 2 cores"),
    # README.md (and docs/studies.md: the same command)
    "fivid study configs/studies/hoffmann_mu_sweep.yaml -o out/hoffmann": slow(
        "a 5-point study with transients (~1 min on a loaded 2-core machine, most of it dask start-up); the "
        "fast test runs docs/studies.md's --quick variant of the same study"),
    "python -m venv .venv && . .venv/bin/activate": skip(
        "creates a virtual environment in the reader's checkout; the tests run in the environment already set up"),
    f'python -m pip install -e ".[all,test]" -c constraints.txt && {_PIPELINE}': skip(
        "pip install needs the network (CI installs before the tests); the pipeline command after it is "
        "docs/pipeline.md's, run by the slow test"),
    "fivid study configs/studies/weak_strong.yaml -o out/weak_strong": slow(
        "the full seed-001 study is 22 points, 9.5 min on 2 workers (docs/studies.md); the slow test runs its "
        "--quick variant (same config and code, 3 points; 78 s on a loaded 2-core machine)",
        run="fivid study configs/studies/weak_strong.yaml -o out/weak_strong --quick"),
    "fivid study configs/studies/ring_mu_sweep.yaml -o out/ring": slow(
        "the full seed-002 study is 25 min on 2 workers (docs/studies.md); the slow test runs its --quick "
        "variant (README: about a minute)", run="fivid study configs/studies/ring_mu_sweep.yaml -o out/ring --quick"),
    "fivid update configs/models/ring.yaml --targets configs/models/targets/ring_seed002.yaml -o ring-fitted.yaml "
    "--json": slow("the seed-002 ring fit: about 20 model evaluations, each a prestressed modal analysis and a "
                   "21-value CEA (8 min on a loaded 2-core machine)"),
    "{ command -v chromium >/dev/null && ldconfig -p | grep -q libudunits2 || { apt-get update -qq && apt-get "
    "install -y -qq chromium libudunits2-0; }; } && python -m pip install -q -e \".[all,test]\" -c constraints.txt "
    "&& python -m pytest -q": skip("apt-get (root, network), pip (network), and it runs this very test suite"),
    # docs/identification.md
    "fivid identify runs/*.nc -o law-inverse.nc --inverse configs/models/triboair_coarse.yaml "
    "--inverse-band 1000 15000": slow("the inverse route runs FE simulations per iteration (minutes)"),
    # docs/pipeline.md
    "fivid study configs/studies/convergence.yaml -o out/convergence": slow(
        "9 transients of the default rig on 5/2/1/0.5 mm meshes (~3 min on 2 free cores, much more when loaded); "
        "the fast test runs its --quick variant, which the table writer below reads as well",
        quick="fivid study configs/studies/convergence.yaml -o out/convergence --quick"),
    _PIPELINE: slow("the whole calibration pipeline (about 2 min on 2 cores, more when loaded)"),
    "fivid run pipelines/calibration.yaml -c configs/runs/lab.yaml --no-progress || mail -s \"fivid exit $?\" "
    "lab@example.org < /dev/null": skip("a crontab entry: the lab's own configs/runs/lab.yaml, and mail"),
    "dask scheduler --host 0.0.0.0 --port 8786": skip("starts a scheduler server that never exits"),
    "dask worker tcp://scheduler-host:8786 --nworkers 4 --nthreads 1": skip(
        "starts workers for a scheduler on another host (network)"),
    "fivid run pipelines/calibration.yaml -c configs/runs/lab.yaml --scheduler tcp://scheduler-host:8786": skip(
        "needs the cluster above and the lab's own configs/runs/lab.yaml"),
    'python -m pip install -e ".[all,test]" -c constraints.txt': skip("pip install needs the network"),
    # docs/roughness.md
    "fivid study configs/studies/roughness_noise.yaml -o out/roughness --quick": slow(
        "4 rough-pair transients of 1.2 ms (under 2 min)"),
    "fivid study configs/studies/roughness_paper.yaml -o out/rough-paper --quick": slow(
        "6 points of the 12 x 2 mm cut (about a minute; tests/study/test_roughness_paper.py runs it too)"),
    "fivid study configs/studies/roughness_paper_cut.yaml -o out/rough-cut": skip(
        "30 points of the 12 x 2 mm cut, about 20 CPU-minutes (docs/roughness.md gives its measured results)"),
    "fivid study configs/studies/roughness_paper.yaml -o out/rough-paper": skip(
        "the 120 x 8 mm study: hours of CPU (docs/roughness.md, 'At the paper's scale: cost')"),
    "fivid study configs/studies/roughness_noise.yaml -o out/roughness": skip(
        "the full seed-003 study is 15-45 min for its 18 points on the shared 2 cores (docs/roughness.md); the "
        "--quick line above runs the same study in the slow test"),
    "fivid identify rough-ra2.nc rough-ra4.5.nc rough-ra10.nc -o law.nc --band 500 20000 --mains-frequency 0 --json":
        skip("needs three 0.1025 s rough-pair runs (about 8 min of solver time each, simulate_rough_run); "
             "tests/study/test_roughness_graded.py::test_a_rough_run_with_a_transducer_goes_through_fivid_identify (slow) "
             "runs that route on one of them"),
    # docs/solver.md
    _SIM: slow(_QUICK_SIM, quick=_SIM.replace("triboair.yaml", "triboair_coarse.yaml").replace('"0.1 s"', '"5 ms"')),
    _SIM_LAW: slow(_QUICK_SIM, quick=_SIM_LAW.replace("triboair.yaml", "triboair_coarse.yaml")
                   .replace('"0.1 s"', '"5 ms"')),
    # docs/studies.md
    "fivid study configs/studies/hoffmann_mu_sweep.yaml -o out/hoffmann-q --quick": slow(
        "dask's LocalCluster start-up is most of a 3-point study's time; the fast test runs it in-process "
        "(--workers 0, documented in docs/studies.md)",
        quick="fivid study configs/studies/hoffmann_mu_sweep.yaml -o out/hoffmann-q --quick --workers 0"),
}

#: documented failures: command -> exit status the docs show
EXIT_CODES = {"fivid profile dektak-1.csv --window 468 733": 2}


def _daq_exports(cwd: Path) -> None:
    from tests.helpers.daq_writers import raw_recording, write_tdms

    channels, metadata = raw_recording()
    write_tdms(cwd, channels, metadata)
    (cwd / "exports").mkdir()
    write_tdms(cwd / "exports", channels, metadata)
    shutil.copy(ROOT / "sample_data" / "twin_daq" / "T01_v5_ra04.csv", cwd / "exports")


def _dektak(cwd: Path) -> None:
    source = REAL_DATA / "profiles" / "dektak-1.csv"
    if not source.is_file():
        (pytest.fail if os.environ.get("CI") else pytest.skip)(f"{source} is not beside the repository")
    shutil.copy(source, cwd)


#: per document: what its examples assume the reader has — commands (run first) or a function of the directory
SETUP: dict[str, list] = {
    "docs/export.md": ["fivid ingest sample_data/R001_v10_ra08.csv -o out/",
                       "fivid psd out/R001.nc --nperseg 1024 -o psd.nc"],  # the sample run is 0.125 s long
    "docs/identification.md": ["fivid ingest sample_data/twin/*.csv -o runs/"],
    "docs/ingest.md": [_daq_exports],
    "docs/solver.md": ["cp configs/laws/sample_truth.nc law.nc"],  # the sample twin's law (Ra 0.4 and 1.6 um)
    "docs/surface.md": [_dektak],
}


# ------------------------------------------------------------------------------------------------ parsing

@dataclass(frozen=True)
class Block:
    """A fenced block: document (relative path), line of its opening fence (1-based), info tag, text."""

    doc: str
    line: int
    lang: str
    text: str


@dataclass(frozen=True)
class Command:
    """One documented command: where, its text as written, its key in DECISIONS, documented output or None."""

    doc: str
    line: int
    text: str
    expected: str | None
    lang: str = "bash"

    @property
    def key(self) -> str:
        if self.lang == "python":  # a Python example: by its first line
            return "python: " + self.text.strip().splitlines()[0]
        return " ".join(re.sub(r"(^|\s)#(\s.*)?$", "", self.text).split())


def fenced_blocks(path: Path) -> list[Block]:
    """Every fenced (```) block of a Markdown file."""
    doc = path.relative_to(ROOT).as_posix()
    blocks, lines = [], path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"\s{0,3}```\s*([\w+-]*)", lines[i])
        if m:
            j = i + 1
            while j < len(lines) and not re.match(r"\s{0,3}```\s*$", lines[j]):
                j += 1
            blocks.append(Block(doc, i + 1, m.group(1).lower(), "\n".join(lines[i + 1:j]) + "\n"))
            i = j
        i += 1
    return blocks


def commands(block: Block) -> list[Command]:
    """The commands of a command block, continuation lines joined."""
    out: list[Command] = []
    lines = block.text.splitlines()
    if block.lang == "python":
        return [Command(block.doc, block.line + 1, block.text, None, "python")] if block.text.strip() else []
    if block.lang == "console":
        for k, line in enumerate(lines):
            if line.startswith("$ "):
                out.append(Command(block.doc, block.line + 1 + k, line[2:].strip(), ""))
            elif out:
                out[-1] = Command(out[-1].doc, out[-1].line, out[-1].text, out[-1].expected + line + "\n")
        return out
    k = 0
    while k < len(lines):
        start, text = k, lines[k]
        while text.rstrip().endswith("\\") and k + 1 < len(lines):
            k += 1
            text = text.rstrip()[:-1].rstrip() + " " + lines[k].strip()
        k += 1
        text = text.strip()
        if not text or text.startswith("#"):
            continue
        if block.lang == "crontab":
            text = text.split(None, 5)[5]
            text = re.sub(r"^cd \S+ && ", "", text)
        out.append(Command(block.doc, block.line + 1 + start, text, None))
    return out


def all_blocks() -> list[Block]:
    return [b for path in DOCS for b in fenced_blocks(path)]


def all_commands() -> list[Command]:
    """The commands and Python examples of every document, in document order."""
    return [c for b in all_blocks() if b.lang in COMMAND_LANGS | {"python"} for c in commands(b)]


# ------------------------------------------------------------------------------------------------ running

def _prepare(cwd: Path, doc: str) -> None:
    for name in COPIED:
        shutil.copytree(ROOT / name, cwd / name)
    for name in LINKED:
        (cwd / name).symlink_to(ROOT / name, target_is_directory=True)
    for step in SETUP.get(doc, []):
        if callable(step):
            step(cwd)
        else:
            _run(step, cwd, f"setup of {doc}", 0, None)


def _run(text: str, cwd: Path, where: str, status: int, expected: str | None, lang: str = "bash") -> None:
    # the interpreter running the tests, not the first 'python' on PATH (a venv's python need not be first):
    # its folder goes first on PATH (pip, dask of the same environment) and python/python3 are functions
    path = os.pathsep.join([os.path.dirname(sys.executable), os.environ.get("PATH", "")])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p]),
               FIVID_DOC_PYTHON=sys.executable, NO_COLOR="1", PATH=path)
    if lang == "python":
        text = f'"$FIVID_DOC_PYTHON" - <<\'FIVID_DOC_EOF\'\n{text}\nFIVID_DOC_EOF'
    script = ('fivid() { "$FIVID_DOC_PYTHON" -m fivid "$@"; }\npython() { "$FIVID_DOC_PYTHON" "$@"; }\n'
              'python3() { "$FIVID_DOC_PYTHON" "$@"; }\nexport -f python python3 fivid\n' + text + "\n")
    proc = subprocess.run(["bash", "-c", script], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=3600, check=False)
    output = proc.stdout + proc.stderr
    assert proc.returncode == status, (
        f"{where}: `{text}` exited {proc.returncode}, the docs expect {status}\n--- output ---\n{output[-4000:]}")
    if expected is not None:
        want = expected.replace("\u2026", "...")
        checker = doctest.OutputChecker()
        flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
        assert checker.check_output(want, proc.stdout + proc.stderr, flags), (
            f"{where}: `{text}`: output differs from the docs\n"
            + checker.output_difference(doctest.Example(text, want), output, flags))


def _plan(doc: str, mode: str) -> list[tuple[Command, str]]:
    """``(command, what to run)`` for one document in ``mode`` 'fast' or 'slow'."""
    plan = []
    for cmd in all_commands():
        if cmd.doc != doc:
            continue
        decision = DECISIONS.get(cmd.key, Decision(cmd.text, cmd.text, "runs as written"))
        run = decision.fast if mode == "fast" else decision.slow
        if run == "":
            run = cmd.text
        if run is not None:
            plan.append((cmd, run))
    return plan


def _run_doc(doc: str, mode: str, tmp_path: Path) -> None:
    plan = _plan(doc, mode)
    _prepare(tmp_path, doc)
    for cmd, run in plan:
        _run(run, tmp_path, f"{cmd.doc}:{cmd.line}", EXIT_CODES.get(cmd.key, 0),
             cmd.expected if run == cmd.text else None, cmd.lang if run == cmd.text else "bash")


def _docs_with(mode: str) -> list[str]:
    """Documents the fast (slow) test runs: the slow one only those with a command listed as slow."""
    docs = sorted({c.doc for c in all_commands()
                   if mode == "fast" or (c.key in DECISIONS and DECISIONS[c.key].slow is not None)})
    return [d for d in docs if _plan(d, mode)]


@pytest.mark.parametrize("doc", _docs_with("fast"))
def test_documented_commands(doc, tmp_path):
    _run_doc(doc, "fast", tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("doc", _docs_with("slow"))
def test_documented_commands_slow(doc, tmp_path):
    _run_doc(doc, "slow", tmp_path)


# ------------------------------------------------------------------------------------------------ bookkeeping

def test_decisions_match_the_docs():
    """Every command listed as slow or skipped is in the docs (so the skipped list is exactly the docs'), and
    every documented exit status names a documented command."""
    keys = {c.key for c in all_commands()}
    assert len(keys) >= 20, keys  # the docs have that many commands; fewer means the parser broke
    stale = sorted(set(DECISIONS) - keys) + sorted(set(EXIT_CODES) - keys)
    assert not stale, f"listed in tests/docs/test_doc_commands.py but not in any document: {stale}"
    skipped = {c.key for c in all_commands() if DECISIONS.get(c.key) and DECISIONS[c.key].fast is None
               and DECISIONS[c.key].slow is None}
    assert skipped == {k for k, d in DECISIONS.items() if d.fast is None and d.slow is None}


def test_every_command_block_has_commands():
    """A command block the parser reads as empty would pass without running anything."""
    empty = [f"{b.doc}:{b.line}" for b in all_blocks() if b.lang in COMMAND_LANGS and not commands(b)]
    assert not empty, f"command blocks with no command: {empty}"


def test_command_blocks_are_tagged():
    """An untagged block that reads like a command would escape the tests: it must say what it is."""
    untagged = [f"{b.doc}:{b.line}" for b in all_blocks() if b.lang == ""
                and re.match(r"\s*(\$ |fivid |python |dask |pip )", b.text)]
    assert not untagged, f"tag these blocks bash/console (a command) or text (a synopsis): {untagged}"


def test_the_parser_reads_each_block_kind():
    """Continuations join, comments drop, console output attaches to its command, cron fields go."""
    bash = Block("x.md", 1, "bash", "# a comment\nfivid a \\\n    --b c   # note\n\nfivid d\n")
    assert [(c.text, c.key, c.line) for c in commands(bash)] == [
        ("fivid a --b c   # note", "fivid a --b c", 3), ("fivid d", "fivid d", 6)]
    console = Block("x.md", 1, "console", "$ fivid a\nout 1\n  out 2\n$ fivid b\n")
    assert [(c.text, c.expected) for c in commands(console)] == [("fivid a", "out 1\n  out 2\n"), ("fivid b", "")]
    cron = Block("x.md", 1, "crontab", "0 2 * * *  cd /lab && fivid run x || mail y\n")
    assert [c.text for c in commands(cron)] == ["fivid run x || mail y"]


def test_commands_run_with_the_interpreter_running_the_tests(tmp_path, monkeypatch):
    """Issue 32: a 'python' first on PATH that is not this interpreter (here one that fails) is not used."""
    fake = tmp_path / "bin"
    fake.mkdir()
    for name in ("python", "python3"):
        (fake / name).write_text("#!/bin/sh\necho wrong python >&2\nexit 97\n")
        (fake / name).chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake}{os.pathsep}{os.environ.get('PATH', '')}")
    probe = "import sys; print(sys.executable)"
    _run(f"python -c '{probe}' && python3 -c '{probe}' && bash -c \"python -c '{probe}'\"", tmp_path, "probe", 0,
         f"{sys.executable}\n{sys.executable}\n{sys.executable}\n")
