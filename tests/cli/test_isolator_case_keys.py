"""The new models' keys in case files (issue 24): each bad value one line naming the file, key, value and valid
range, exit 2, nothing written; a campaign of a model or damper it does not fit says so in one line."""

import pytest
from typer.testing import CliRunner

from quickrelease.cli import app

runner = CliRunner()
PENDULUM = dict(radius="'2.5 m'", friction_slow="0.02", friction_fast="0.06", rate="'30 s/m'")
BOUCWEN = dict(post_yield_stiffness="'1.6 MN/m'", characteristic_strength="'400 kN'", yield_displacement="'25 mm'",
               shape="1.0")


def table(model: str, values: dict[str, str]) -> str:
    return (f"[building]\nmodel = '{model}'\nmass = '900 t'\ndisplacement = '200 mm'\n"
            + "".join(f"{k} = {v}\n" for k, v in values.items()))


BAD = [("pendulum", "radius", "'1e308 m'"), ("pendulum", "radius", "'1e-300 m'"), ("pendulum", "radius", "'-2.5 m'"),
       ("pendulum", "radius", "'0 m'"), ("pendulum", "radius", "'nan m'"), ("pendulum", "friction_slow", "-0.01"),
       ("pendulum", "friction_fast", "nan"), ("pendulum", "rate", "'1e308 s/m'"), ("pendulum", "rate", "'-1 s/m'"),
       ("boucwen", "post_yield_stiffness", "'1e308 N/m'"), ("boucwen", "characteristic_strength", "'0 N'"),
       ("boucwen", "yield_displacement", "'0 m'"), ("boucwen", "yield_displacement", "'1e308 m'"),
       ("boucwen", "shape", "100"), ("boucwen", "shape", "nan")]


@pytest.mark.parametrize("model, key, value", BAD, ids=[f"{m}-{k}={v}" for m, k, v in BAD])
def test_a_bad_value_of_a_new_key_is_one_line_naming_it(model, key, value, tmp_path):
    values = {**(PENDULUM if model == "pendulum" else BOUCWEN), key: value}
    (tmp_path / "c.toml").write_text(table(model, values), encoding="utf-8")
    r = runner.invoke(app, ["synth", str(tmp_path / "c.toml"), "--building", "--out", str(tmp_path / "o.csv")])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.stderr
    assert "c.toml" in lines[0] and f"[building] {key} = " in lines[0]
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize("model, extra, words", [
    ("quadratic", {"period": "'2 s'"}, "model = 'quadratic'"),
])
def test_a_campaign_of_a_model_it_does_not_fit_says_so(model, extra, words, tmp_path):
    """The pendulum, Bouc-Wen and power-damper campaigns are fitted (tests/studies/test_building_campaign_isolators.py);
    what remains refused is refused in one line naming the file and key, before any record is read, exit 2."""
    text = table(model, extra).replace("displacement = '200 mm'\n", "")
    text += "[building.record]\ntime = 't_s'\n[building.record.channels]\nx = { column = 'x_mm', unit = 'mm' }\n"
    text += "".join(f"[[tests]]\nname = 'R{i}'\ndisplacement = '{50 * i} mm'\nrecord = 'r.csv'\n" for i in (1, 2, 3))
    (tmp_path / "camp.toml").write_text(text, encoding="utf-8")
    r = runner.invoke(app, ["campaign", str(tmp_path / "camp.toml"), "--out", str(tmp_path / "out")])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1 and words in lines[0] and "camp.toml" in lines[0], r.stderr
    assert "Traceback" not in r.output and not (tmp_path / "out").exists()


# What is not a quantity (non-finite, empty, a bare unit, a boolean, a non-ASCII number or unit) names the key,
# its value and the key's own range (before: a grammar's example, "e.g. '1598 kN'", or no range at all).
LRD = dict(post_yield_stiffness="'1.6 MN/m'", characteristic_strength="'400 kN'", yield_displacement="'25 mm'",
           shape="1.0", damping="'power'", damping_coefficient="'200 kN'", damping_exponent="0.5")
CONSTANT = dict(radius="'2.5 m'", friction_coefficient="0.04")
#: key -> (model, the other keys, its range as the user's guide states it)
RANGES = {"radius": ("pendulum", PENDULUM, "[0.01, 1000] m"), "friction_slow": ("pendulum", PENDULUM, "[0, 1]"),
          "friction_fast": ("pendulum", PENDULUM, "[0, 1]"), "rate": ("pendulum", PENDULUM, "[0, 1e4] s/m"),
          "friction_coefficient": ("pendulum", CONSTANT, "[0, 1]"),
          "post_yield_stiffness": ("boucwen", BOUCWEN, "[0.1, 100] s"),
          "characteristic_strength": ("boucwen", BOUCWEN, "(0, m g]"),
          "yield_displacement": ("boucwen", BOUCWEN, "[1e-5, 1] m"), "shape": ("boucwen", BOUCWEN, "[0.5, 25]"),
          "damping_coefficient": ("boucwen", LRD, "[0, 10 m g]"),
          "damping_exponent": ("boucwen", LRD, "[0.05, 2]")}
NOT_QUANTITIES = ["nan", "-inf", "'nan m'", "''", "'kN'", "true", "'\uff12.\uff15'", "'2.5 \u00e9'"]


@pytest.mark.parametrize("value", NOT_QUANTITIES)
@pytest.mark.parametrize("key", sorted(RANGES))
def test_what_is_not_a_quantity_names_the_keys_range(key, value, tmp_path):
    model, others, valid = RANGES[key]
    (tmp_path / "c.toml").write_text(table(model, {**others, key: value}), encoding="utf-8")
    r = runner.invoke(app, ["synth", str(tmp_path / "c.toml"), "--building", "--out", str(tmp_path / "o.csv")])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.stderr
    assert f"[building] {key} = " in lines[0] and valid in lines[0], lines[0]
    assert "e.g. '1598 kN'" not in lines[0]
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize("model, values, key, words", [
    ("pendulum", {**CONSTANT, "friction_coefficient": "1e308"}, "friction_coefficient", "[0, 1]"),
    ("pendulum", {**CONSTANT, "friction_coefficient": "1.5"}, "friction_coefficient", "[0, 1]"),
    ("boucwen", {**BOUCWEN, "friction_coefficient": "1e6"}, "friction_coefficient", "[0, 1]"),
    ("pendulum", {k: v for k, v in PENDULUM.items() if k != "friction_slow"}, "friction_fast",
     "without friction_slow"),
    ("pendulum", {"radius": "'2.5 m'", "rate": "'30 s/m'"}, "rate", "without friction_slow"),
])
def test_a_friction_the_model_cannot_take_is_refused(model, values, key, words, tmp_path):
    """friction_coefficient above 1 (1e308: an infinite friction force), and Constantinou's friction_fast or rate
    without its friction_slow (before: mu_slow silently 0), for the fit's command and synth alike."""
    (tmp_path / "c.toml").write_text(table(model, values), encoding="utf-8")
    for args in (["synth", str(tmp_path / "c.toml"), "--building", "--out", str(tmp_path / "o.csv")],
                 ["plan", str(tmp_path / "c.toml")]):
        r = runner.invoke(app, args)
        lines = r.stderr.strip().splitlines()
        assert r.exit_code == 2 and len(lines) == 1, r.stderr
        assert f"[building] {key} = " in lines[0] and words in lines[0], lines[0]
    assert not (tmp_path / "o.csv").exists()


def test_a_key_given_twice_is_named(tmp_path):
    text = table("pendulum", PENDULUM) + "radius = '3 m'\n"
    (tmp_path / "c.toml").write_text(text, encoding="utf-8")
    r = runner.invoke(app, ["synth", str(tmp_path / "c.toml"), "--building", "--out", str(tmp_path / "o.csv")])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.stderr
    assert "not valid TOML" in lines[0] and "line 9 reads \"radius = '3 m'\"" in lines[0], lines[0]


@pytest.mark.parametrize("model, values, key", [
    ("pendulum", {"radius": "'2.5 m'", "friction_coefficient": "1"}, "friction_coefficient = 1"),
    # W d0 / R = 0.2 m / 2.5 m = 8 % of the weight, below mu_slow = 10 %
    ("pendulum", {**PENDULUM, "friction_slow": "0.1", "friction_fast": "0.1"}, "friction_slow = 0.1"),
    # k d0 = 900 t (2 pi / 2 s)^2 0.2 m = 1.78 MN, below 2 MN
    ("linear", {"period": "'2 s'", "friction": "'2 MN'"}, "friction = 2e+06 N"),
])
def test_a_building_its_friction_holds_names_the_friction_key(model, values, key, tmp_path):
    (tmp_path / "c.toml").write_text(table(model, values), encoding="utf-8")
    r = runner.invoke(app, ["synth", str(tmp_path / "c.toml"), "--building", "--out", str(tmp_path / "o.csv")])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.stderr
    assert "never moves" in lines[0] and f"[building] {key})" in lines[0], lines[0]
    assert not (tmp_path / "o.csv").exists()
