"""Study kinds as plug-ins (issue 29 item 2): a toy kind registered from outside fivid runs through the config
loader, the runner and the report; the shipped kinds are found by name or by their config; the runner, the config
loader and the report name no kind.

The toy kind is a spring-held block pressed on a belt (SYNTHETIC, closed form): it slips when the spring force
reaches the friction force, at the spring extension ``x = mu N / k``. Its summary fits ``x`` as a power law of the
normal load: the exponent is 1 and the prefactor ``mu / k`` to float round-off (OLS on exact data).
"""

import ast
import json
from pathlib import Path

import numpy as np
import pytest

from fivid.config_layer import ConfigModel, Quantity
from fivid.errors import ConfigError
from fivid.study import load_study, open_study, register_study_kind, registered_kinds, run_study
from fivid.study.fits import power_law_fit
from fivid.study.kind import StudyKind, unregister_study_kind

ROOT = Path(__file__).resolve().parents[2]


class SpringBlockParameters(ConfigModel):
    stiffness: Quantity("N m-1", positive=True, bare_is_si=True)


class SpringBlock:
    """The toy kind: what a new kind module holds (docs/studies.md, "Adding a study kind")."""

    name = "spring_block"
    description = "a spring-held block on a belt: the extension at which it slips, x = mu N / k"
    lumped = True
    section = ("system", "parameters")
    config = SpringBlockParameters
    point_keys = (("slip_extension", "slip_extension"),)

    def guess(self, data):
        return False

    def check(self, cfg):
        missing = [a for a in ("mu", "normal_load") if getattr(cfg.sweep, a) is None]
        return [("sweep", f"a spring-block study sweeps {' and '.join(missing)}")] if missing else []

    def settings(self, section):
        return section.model_dump()

    def system(self, study):
        return {"stiffness": study.lumped["parameters"]["stiffness"]}

    def evaluate(self, system, tasks, conditions):
        import xarray as xr

        x = float(conditions["mu"]) * float(conditions["normal_load"]) / system["stiffness"]
        return xr.Dataset({"slip_extension": ((), x, {"units": "m", "long_name": "spring extension at slip"})})

    def cea(self, study, mu):
        raise ConfigError("a spring-held block has no mode coupling to analyse", key="cea")

    def summarise(self, study, ds, points):
        fit = power_law_fit(points, "slip_extension")
        return {"fits": {"slip_extension": fit}} if fit else {}

    def report(self, page, ds, summary):
        fit = summary["fits"]["slip_extension"]
        page.heading("Spring-held block", level=3)
        page.paragraph(f"slip extension ∝ N^{fit['exponents']['normal_load']['value']:.6f}")


@pytest.fixture
def toy_kind():
    kind = register_study_kind(SpringBlock())
    yield kind
    unregister_study_kind(kind.name)


def _config(**over):
    cfg = {"fivid-study": 1, "kind": "spring_block", "name": "toy",
           "system": {"lumped": "spring_block", "parameters": {"stiffness": "2 kN/m"}},
           "sweep": {"mu": {"values": [0.2, 0.5]}, "normal_load": {"values": ["1 N", "2 N", "8 N"]},
                     "combine": "grid"}}
    cfg.update(over)
    return cfg


def test_a_registered_kind_runs_through_the_runner_and_the_report(toy_kind, tmp_path):
    assert isinstance(toy_kind, StudyKind) and registered_kinds()["spring_block"] is toy_kind
    study = load_study(_config())
    assert study.kind is toy_kind and study.lumped["parameters"] == {"stiffness": 2000.0}
    summary = run_study(study, tmp_path / "out", workers=0, progress=False)
    assert summary["kind"] == "spring_block" and summary["n_done"] == 6
    for p in summary["points"]:
        assert p["slip_extension"] == pytest.approx(p["mu"] * p["normal_load"] / 2000.0, rel=1e-15)
    fit = summary["fits"]["slip_extension"]
    assert fit["exponents"]["normal_load"]["value"] == pytest.approx(1.0, abs=1e-12)
    assert set(fit["exponents"]) == {"normal_load"}  # mu is not a power-law axis (it only scatters the fit)
    assert fit["prefactor"] == pytest.approx(np.sqrt(0.2 * 0.5) / 2000.0, rel=1e-12)  # geometric mean of mu / k
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["fits"] == summary["fits"]
    ds = open_study(tmp_path / "out" / "study.nc")
    last = ds.sel(mu=0.5).sel(normal_load=8.0)
    np.testing.assert_allclose(last["slip_extension"], 0.5 * 8.0 / 2000.0, rtol=1e-15)
    assert "slip extension ∝ N^1.000000" in (tmp_path / "out" / "report.html").read_text(encoding="utf-8")


def test_the_kinds_section_and_checks_are_its_own(toy_kind):
    with pytest.raises(ConfigError) as err:
        load_study(_config(system={"lumped": "spring_block", "parameters": {"stiffness": "2 kg"}}))
    assert err.value.key == "system.parameters.stiffness"
    with pytest.raises(ConfigError) as err:
        load_study(_config(sweep={"mu": {"values": [0.2]}}))
    assert err.value.key == "sweep" and "normal_load" in err.value.message
    with pytest.raises(ConfigError) as err:
        load_study(_config(kind="no_such_kind"))
    assert err.value.key == "kind" and "spring_block" in err.value.message and "hoffmann" in err.value.message


def test_a_kind_missing_a_method_is_refused():
    class Half:
        name = "half"

    with pytest.raises(ValueError, match="lacks description"):
        register_study_kind(Half())


@pytest.mark.parametrize("study, kind", [("hoffmann_mu_sweep", "hoffmann"), ("ring_mu_sweep", "ring"),
                                         ("weak_strong", "weak_strong"), ("convergence", "convergence"),
                                         ("roughness_noise", "roughness"), ("roughness_paper", "roughness"),
                                         ("roughness_paper_cut", "roughness")])
def test_shipped_studies_name_their_kind_and_the_guess_agrees(study, kind):
    """Each shipped study says its kind; without the ``kind:`` line the registry's guess finds the same one."""
    import yaml

    path = ROOT / "configs" / "studies" / f"{study}.yaml"
    assert load_study(path).kind.name == kind
    data = yaml.safe_load(path.read_text())
    data.pop("kind")
    data.pop("quick", None)
    if "model" in data["system"]:  # the mapping has no folder: its files absolute
        data["system"]["model"] = str((path.parent / data["system"]["model"]).resolve())
    law = (data.get("points") or {}).get("transient", {}).get("law")
    if law:
        data["points"]["transient"]["law"] = str((path.parent / law).resolve())
    assert load_study(data).kind.name == kind  # (ring and weak/strong set one mesh factor: no refinement)


def _kind_names_in(path: Path) -> list[str]:
    names = set(registered_kinds())
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [f"{path.name}:{n.lineno}: {n.value!r}" for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and n.value in names]


def test_runner_config_and_report_know_no_kind_by_name():
    """No if-chain on kind names: the modules that run, read and report studies hold no kind's name as a string
    (the shipped kinds live in fivid/study/kinds/, one module each)."""
    bad = [hit for name in ("runner.py", "config.py", "report.py", "kind.py")
           for hit in _kind_names_in(ROOT / "fivid" / "study" / name)]
    assert not bad, bad
    assert _kind_names_in(ROOT / "fivid" / "study" / "kinds" / "hoffmann.py")  # the check can find one
