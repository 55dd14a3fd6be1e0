"""One vocabulary across commands (docs/conventions.md, "Defaults and words"): each word and default
decided once, and every command reading it from there."""

from __future__ import annotations

import argparse
import importlib
import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from vissim.atv.virtual import AtvApparatus, VirtualSubject
from vissim.bench.atv.tube import AtvConfig, AtvEye
from vissim.checks import (DEFAULT_WAVELENGTH_NM, EYE_PUPIL_RANGE_MM, eye_pupil_diameter_mm, pupil_diameter_mm,
                           size_text)
from vissim.cli import build_parser, main
from vissim.errors import VissimInputError
from vissim.imageio import write_image
from vissim.optics.eyes.defaults import PHOTOPIC_FOCUS_NM
from vissim.optics.rx.glass import D_LINE_NM
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.trial_lens import EYE_VERTEX_DISTANCE_MM
from vissim.provenance import make_provenance
from vissim.thesis import THESIS_VERTEX_DISTANCE_MM
from vissim.units import mm_to_m

ROOT = Path(__file__).resolve().parents[1]


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def subcommands(parser=None, path=()):
    """(command path, parser) of every leaf sub-command."""
    parser = parser or build_parser()
    children = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not children:
        yield path, parser
        return
    for name, child in children[0].choices.items():
        yield from subcommands(child, (*path, name))


def option(parser, flag):
    return next((a for a in parser._actions if flag in a.option_strings), None)


# -- sizes --------------------------------------------------------------------------------------


def test_a_size_reads_width_by_height_from_an_array_shape():
    assert size_text((480, 640)) == "640 × 480 px (width × height)"
    assert size_text((480, 640, 3)) == "640 × 480 px (width × height)"  # channels are not a dimension of size
    assert size_text((64, 64)) == "64 × 64 px"
    assert size_text((297.0, 210.0), "mm") == "210 × 297 mm (width × height)"
    assert size_text((8.25, 29.2), "mm") == "29.2 × 8.25 mm (width × height)"


SIZE_LIKE = re.compile(r"\{[^{}]*\}\s*(?:x|×)\s*\{[^{}]*\}\s*(?:px|mm|texel)|shape[^{}]*\}\s*px")


def test_no_message_formats_a_size_but_the_helper():
    # An f-string that writes '{a} x {b} px' or '{shape} px' is a size formatted by hand, in
    # whichever order its author chose; every one goes through size_text.
    hand_made = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
                 for path in sorted((ROOT / "vissim").rglob("*.py")) if path.name != "checks.py"
                 for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
                 if SIZE_LIKE.search(line)]
    assert hand_made == []


def test_success_lines_and_errors_say_sizes_the_same_way(capsys, tmp_path):
    code, out, _ = run(capsys, "chart", "--logmar", "1", "-o", tmp_path / "c.exr")
    assert code == 0 and "chart 550 × 150 px (width × height) at 1 arcmin/px" in out
    image = tmp_path / "wide.exr"
    write_image(image, np.full((20, 40), 0.5, np.float32), provenance=make_provenance(command="test", arcmin_per_px=1.0))
    code, _, err = run(capsys, "blur-depth", image, tmp_path / "missing.npy", "--rx", "-1", "--pupil-mm", "3",
                       "--crop-px", "10", "-o", tmp_path / "o.exr")
    assert code == 2 and "cannot crop 10 px from every side of a 40 × 20 px (width × height) image" in err


# -- defaults -----------------------------------------------------------------------------------


def test_every_wavelength_default_is_the_one_constant():
    # The bench's glass is traced at its d line (render bench --optics wave, bench wavefront), stated in
    # their help; blur's RGB channels have their own wavelengths (mono images take the constant); a
    # schematic eye is reported at its model's reference wavelength (Escudero-Sanz's 543 nm), said in its help;
    # an eye's render is lit at the constant, as the eye campaign is.
    seen = []
    for path, parser in subcommands():
        for flag in ("--wavelength-nm", "--lca-reference-nm"):
            action = option(parser, flag)
            if action is None:
                continue
            seen.append(path)
            if path in (("render", "bench"), ("bench", "wavefront")):
                assert action.default in (None, D_LINE_NM) and "the d line" in action.help
            elif path == ("population",):  # the published human MTFs' light, V(λ)'s peak
                assert action.default is None and f"default {PHOTOPIC_FOCUS_NM:g}: V(λ)'s peak" in action.help
            elif path == ("eye",):
                assert action.default is None and "the model's reference wavelength" in action.help
            elif action.default is None:
                assert path in (("blur",), ("psf",), ("render", "eye")) and f"default {DEFAULT_WAVELENGTH_NM:g}" in action.help
            else:
                assert float(action.default) == DEFAULT_WAVELENGTH_NM, (path, flag)
                assert f"default {DEFAULT_WAVELENGTH_NM:g}" in action.help, (path, flag)
    assert {("psf",), ("blur-depth",), ("fit-rx",), ("atv", "simulate"), ("eye",), ("render", "eye")} <= set(seen)
    assert AtvApparatus().wavelength_nm == DEFAULT_WAVELENGTH_NM  # was 555 nm: no reason recorded


def test_vertex_distances_are_the_camera_and_the_eye_constants():
    parsers = dict(subcommands())
    assert THESIS_VERTEX_DISTANCE_MM == 10.0 and EYE_VERTEX_DISTANCE_MM == 15.0
    assert option(parsers[("trial-lens",)], "--vertex-mm").default == THESIS_VERTEX_DISTANCE_MM
    for path in (("render", "atv"), ("atv", "simulate")):
        assert f"default {EYE_VERTEX_DISTANCE_MM:g}" in option(parsers[path], "--vertex-mm").help
    assert AtvApparatus().trial_lens_vertex_mm == EYE_VERTEX_DISTANCE_MM
    assert AtvConfig().trial_lens_distance_mm == EYE_VERTEX_DISTANCE_MM
    scene = tomllib.loads((ROOT / "scenes" / "atv_tube.toml").read_text(encoding="utf-8"))
    assert scene["trial_lens"]["vertex_distance_mm"] == EYE_VERTEX_DISTANCE_MM
    dslr = tomllib.loads((ROOT / "scenes" / "dslr_bench.toml").read_text(encoding="utf-8"))
    assert dslr["holder"]["vertex_distance_mm"] == THESIS_VERTEX_DISTANCE_MM


# -- pupils -------------------------------------------------------------------------------------


def test_an_eye_pupil_and_an_entrance_pupil_are_two_ranges():
    assert EYE_PUPIL_RANGE_MM == (1.0, 10.0)
    assert eye_pupil_diameter_mm(9.0) == 9.0 and pupil_diameter_mm(30.0) == 30.0  # 9 mm eye; a 30 mm lens
    with pytest.raises(VissimInputError, match=r"within 1-10 mm \(a human eye's pupil\), got 30 mm"):
        eye_pupil_diameter_mm(30.0)
    assert AtvEye(pupil_diameter_mm=9.0).pupil_diameter_mm == 9.0  # render atv refused 9 mm
    with pytest.raises(VissimInputError, match="a human eye's pupil"):
        VirtualSubject(Prescription(0.0), 12.0)


@pytest.mark.parametrize("argv", [
    ["atv", "simulate", "--rx", "+1", "--pupil-mm", "12", "-o", "{tmp}/s"],
    ["render", "atv", "--pupil-mm", "12", "-o", "{tmp}/a.exr"],
    ["render", "depth", str(ROOT / "scenes" / "depth_panels.toml"), "--pupil-mm", "12", "-o", "{tmp}/d.exr"],
])
def test_commands_whose_viewer_is_an_eye_refuse_a_pupil_no_eye_has(capsys, tmp_path, argv):
    code, out, err = run(capsys, *[a.format(tmp=tmp_path) for a in argv])
    assert code == 2 and err.count("\n") == 1 and "within 1-10 mm (a human eye's pupil), got 12 mm" in err
    assert not any(tmp_path.iterdir())


# -- words --------------------------------------------------------------------------------------


def test_the_atv_options_say_amplitude_and_the_slopes_variable():
    parsers = dict(subcommands())
    simulate, procedure = parsers[("atv", "simulate")], parsers[("atv", "run")]
    assert option(simulate, "--accommodation-diopters") is None  # there it meant an amplitude
    assert "amplitude" in option(simulate, "--accommodation-amplitude-diopters").help
    assert option(simulate, "--slope") is None and option(procedure, "--slope") is None
    assert "luminance" in option(simulate, "--luminance-slope").help
    assert "code value" in option(procedure, "--code-value-slope").help
    # Everywhere else --accommodation-diopters is the accommodation exerted.
    for path, parser in parsers.items():
        action = option(parser, "--accommodation-diopters")
        if action is not None:
            assert "amplitude" not in action.help and "accommodation" in action.help, path


def test_blur_depth_help_states_one_accommodation_default(capsys):
    assert main(["blur-depth", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert text.count("relaxed, 0 D exerted") == 1 and "default relaxed" not in text
    assert "default the depth at the image centre" not in text


def test_trial_lens_prints_one_cylinder_form(capsys):
    # A plus-cylinder lens: every power the command prints is in minus cylinder.
    code, out, _ = run(capsys, "trial-lens", "--sphere", "1", "--cylinder", "2", "--axis", "30")
    assert code == 0 and "minus-cylinder form" in out.splitlines()[0]
    cylinders = [float(c) for c in re.findall(r"[+-]\d+\.\d+ ([+-]\d+\.\d+) x \d", out)]
    assert len(cylinders) == 3 and all(c < 0 for c in cylinders)  # the lens, the added power, the camera's Rx
    code, out, _ = run(capsys, "trial-lens", "--sphere", "1", "--cylinder", "2", "--axis", "30", "--json")
    record = json.loads(out)
    assert record["cylinder_form"] == "minus"
    for text in (record["lens"]["marked_power"], record["added_power"], record["camera_prescription"]):
        assert Prescription.parse(text).cylinder_diopters < 0, text
    lens = record["lens"]  # +1.00 +2.00 x 30 is +3.00 -2.00 x 120
    assert (lens["sphere_diopters"], lens["cylinder_diopters"], lens["axis_deg"]) == pytest.approx((3.0, -2.0, 120.0))


def test_a_render_without_a_lens_says_so(capsys, tmp_path):
    from vissim.render.backend import choose_variant

    if choose_variant("mono").variant.startswith("scalar"):
        pytest.skip("no JIT Mitsuba variant")
    code, out, _ = run(capsys, "render", "bench", "--letter", "C", "--spp", "4", "--size", "21x21", "-o", tmp_path / "r.exr")
    assert code == 0 and out.rstrip().endswith("no trial lens") and "None" not in out


# -- one spelling per concept (vissim.vocabulary.CONCEPTS) -----------------------------------------

import inspect  # noqa: E402

from vissim.vocabulary import CONCEPTS, RENAMED_KEYS  # noqa: E402

UNIT_SUFFIXES = ("_arcmin_per_px", "_diopters", "_mm", "_nm", "_deg", "_px", "_um", "_m")
SURFACES = {"flag": "flag", "campaign": "campaign_key", "scene": "scene_key", "api": "api"}
#: Spellings not yet renamed (issue #36): none left (the public API's were renamed too). A (surface, concept,
#: spelling) listed here must be one the checker reports; any other it reports fails.
KNOWN_LEFT: set[tuple[str, str, str]] = set()


def concept_of(name: str):
    """The concept (`CONCEPTS`) a flag, key or parameter name spells, or None."""
    name = name.lstrip("-").replace("-", "_").lower()
    stem = next((name[: -len(s)] for s in UNIT_SUFFIXES if name.endswith(s) and len(name) > len(s)), name)
    for concept in CONCEPTS:
        if any(x in name for x in concept.excluding):
            continue
        if any(stem == w or stem.startswith(w + "_") or stem.endswith("_" + w) for w in concept.words):
            return concept
    return None


def flag_names(parser=None) -> dict[str, set]:
    """Every long option of every leaf command: {spelling: {command paths}}."""
    out: dict[str, set] = {}
    for path, leaf in subcommands(parser):
        for action in leaf._actions:
            for flag in action.option_strings:
                if flag.startswith("--") and flag != "--help":
                    out.setdefault(flag, set()).add(" ".join(path))
    return out


def campaign_keys() -> dict[str, set]:
    """Every key the campaign loaders declare: {key: {where}}."""
    from dataclasses import fields

    from vissim.validation.depth import schema as depth
    from vissim.validation.dslr import loader as dslr_loader
    from vissim.validation.dslr.schema import CampaignSettings
    from vissim.validation.engine.fields import LENS_KEYS
    from vissim.validation.eye import schema as eye
    from vissim.validation.population import schema as population

    declared = {
        "eye [[item]]": eye.ITEM_KEYS, "eye [campaign]": [f.name for f in fields(eye.EyeSettings)],
        "depth [[config]]": depth.CONFIG_KEYS, "depth camera": tuple(depth.CAMERA_FIELDS),
        "depth [campaign]": [f.name for f in fields(depth.DepthCampaignSettings)],
        "dslr [[item]]": dslr_loader.ITEM_KEYS, "dslr [[sweep]]": dslr_loader.SWEEP_KEYS,
        "dslr [campaign]": [f.name for f in fields(CampaignSettings)],
        "population [campaign]": population.HEAD_KEYS, "a lens table": LENS_KEYS,
    }
    return _by_key(declared)


def _by_key(declared: dict) -> dict[str, set]:
    """{where: keys} turned round: {key: {where}}."""
    out: dict[str, set] = {}
    for where, keys in declared.items():
        for key in keys:
            out.setdefault(key, set()).add(where)
    return out


def scene_keys() -> dict[str, set]:
    """Every key the scene loaders declare: {key: {where}}."""
    from vissim.bench import scene_toml
    from vissim.bench.atv import scene_files as atv
    from vissim.bench.depth import scene_files as depth
    from vissim.bench.dslr import scene_files as dslr
    from vissim.render.eye_scene_files import EYE_SCENE_KEYS

    declared = {f"eye [{t}]": tuple(keys) for t, keys in EYE_SCENE_KEYS.items()}
    declared |= {f"depth {n}": tuple(getattr(depth, n)) for n in ("_IMAGE", "_SAMPLING", "_EYE", "_CAMERA", "_PANEL", "_TILTED")}
    declared |= {f"dslr {n}": tuple(getattr(dslr, n)) for n in ("_CAMERA", "_HOLDER", "_IMAGE", "_SAMPLING", "_CHART")}
    declared |= {"atv [tube]": tuple(atv._ATV_TUBE_KEYS), "a trial lens": tuple(scene_toml._LENS)}
    source = Path(atv.__file__).read_text(encoding="utf-8")  # the ATV eye's and lens's keys are written inline
    declared["atv [eye], [trial_lens]"] = tuple(re.findall(r'"(\w+_(?:mm|diopters|deg)|prescription)"', source))
    return _by_key(declared)


def api_names() -> dict[str, set]:
    """Every parameter of the public API (``vissim.__all__``: functions, classes' constructors and methods)."""
    import vissim

    out: dict[str, set] = {}
    for public in vissim.__all__[1:]:
        obj = getattr(vissim, public)
        members = [(public, obj.__init__ if inspect.isclass(obj) else obj)]
        if inspect.isclass(obj):
            members += [(f"{public}.{k}", getattr(obj, k)) for k, v in vars(obj).items()
                        if not k.startswith("_") and (callable(v) or isinstance(v, (classmethod, staticmethod)))]
        for where, member in members:
            try:
                parameters = inspect.signature(member).parameters
            except (TypeError, ValueError):
                continue
            for name in parameters:
                if name not in ("self", "cls"):
                    out.setdefault(name, set()).add(where)
    return out


def vocabulary_problems(surfaces: dict[str, dict[str, set]]) -> set[tuple[str, str, str]]:
    """(surface, concept, spelling) for every spelling of a concept that is not its one spelling on that surface."""
    problems = set()
    for surface, names in surfaces.items():
        for name in names:
            concept = concept_of(name)
            if concept is None:
                continue
            expected = getattr(concept, SURFACES[surface])
            spelled = name.lstrip("-").replace("-", "_") if surface == "flag" else name
            want = None if expected is None else expected.lstrip("-").replace("-", "_")
            if spelled != want:
                problems.add((surface, concept.name, name))
    return problems


def all_surfaces(parser=None) -> dict[str, dict[str, set]]:
    return {"flag": flag_names(parser), "campaign": campaign_keys(), "scene": scene_keys(), "api": api_names()}


def test_every_concept_has_one_spelling_per_surface():
    problems = vocabulary_problems(all_surfaces())
    assert problems - KNOWN_LEFT == set(), sorted(problems - KNOWN_LEFT)
    assert KNOWN_LEFT <= problems, f"renamed since: drop {sorted(KNOWN_LEFT - problems)} from KNOWN_LEFT"


def test_the_checker_finds_a_planted_second_spelling(monkeypatch):
    # A command that spells the pupil --pupil-diameter-mm, and a campaign kind that keeps vertex_mm.
    from vissim.validation.population import schema as population

    parser = build_parser()
    leaf = dict(subcommands(parser))[("psf",)]
    leaf.add_argument("--pupil-diameter-mm", type=float, help="planted (default none)")
    monkeypatch.setattr(population, "HEAD_KEYS", (*population.HEAD_KEYS, "vertex_mm"))
    problems = vocabulary_problems(all_surfaces(parser))
    assert ("flag", "entrance pupil diameter", "--pupil-diameter-mm") in problems
    assert ("campaign", "vertex distance (trial or spectacle lens to the viewer)", "vertex_mm") in problems
    assert ("flag", "entrance pupil diameter", "--pupil-mm") not in problems  # the one spelling stays right


def test_the_concepts_table_is_the_conventions_table():
    text = (ROOT / "docs" / "conventions.md").read_text(encoding="utf-8")
    for concept in CONCEPTS:
        flag = f"`{concept.flag}`" if concept.flag else "—"
        row = next((line for line in text.splitlines() if line.startswith(f"| {concept.name} | {flag} |")), None)
        assert row is not None, concept.name
        for spelling in (concept.flag, concept.campaign_key, concept.scene_key, concept.api):
            assert (f"`{spelling}`" if spelling else "—") in row, (concept.name, spelling)


@pytest.mark.parametrize("old, table", [
    ("vertex_mm", '[campaign]\nkind = "population"\ndataset = "jaeken-artal-2012"\nvertex_mm = 12.0\n'),
    ("pupil_mm", '[campaign]\nkind = "eye"\n[[item]]\nname = "a"\npupil_mm = 3.0\n'),
    ("light", '[campaign]\nkind = "eye"\n[[item]]\nname = "a"\nlight = "photopic"\n'),
    ("spheres", '[[sweep]]\nname = "s"\nletter = ["K"]\nspheres = [1.0]\n'),
    ("axis", '[[item]]\nletter = "K"\nlenses = [{ cylinder_diopters = 1.0, axis = 90 }]\n'),
    ("eye", '[campaign]\nkind = "depth"\n[[config]]\nscene = "../scenes/depth_panels.toml"\neye = "plano"\n'),
])
def test_a_renamed_campaign_key_is_refused_in_one_line_naming_the_new(capsys, tmp_path, old, table):
    path = tmp_path / "old.toml"
    text = table.replace("../scenes/depth_panels.toml", str(ROOT / "scenes" / "depth_panels.toml"))
    path.write_text(text, encoding="utf-8")
    code, _, err = run(capsys, "validate", path, "-o", tmp_path / "run")
    new = RENAMED_KEYS[old].split(" ", 1)[0]
    assert code == 2 and err.count("\n") == 1 and f"'{old}' is now '{new}'" in err, err


# -- every option's help states its default --------------------------------------------------------

#: Options with nothing to default (switches, outputs, inputs named by the user) need not say one.
NO_DEFAULT = {"--help", "--output", "--overwrite", "--json", "--scene", "--chart", "--scheduler", "--reference",
              "--all-in-focus", "--depth", "--variant"}


#: Options whose help does not yet say their default (issue #36): none left. One listed here must be one the
#: test finds; any other it finds fails.
HELP_DEFAULT_LEFT: set[str] = set()


def test_every_option_help_states_its_default():
    missing = []
    for path, leaf in subcommands():
        for action in leaf._actions:
            flag = next((f for f in action.option_strings if f.startswith("--")), None)
            if flag is None or flag in NO_DEFAULT or isinstance(action, argparse._StoreTrueAction):
                continue
            if action.required:
                continue
            help_text = " ".join((action.help or "").split()).lower()
            group_text = ""
            if not re.search(r"default|\(none|\(optional|if omitted|required|recorded only|with --|"
                             r"or the |in place of|override|needs --|goes with", help_text + group_text):
                missing.append(f"{' '.join(path)} {flag}")
    assert set(missing) - HELP_DEFAULT_LEFT == set(), "\n".join(sorted(set(missing) - HELP_DEFAULT_LEFT))
    assert HELP_DEFAULT_LEFT <= {m.split(":")[0] for m in missing}, sorted(HELP_DEFAULT_LEFT - {m.split(":")[0] for m in missing})


# -- --json on every command that computes numbers ----------------------------------------------------

#: Commands that only print help or hand over to another program (``atv run`` has --json with a simulated observer;
#: with a person its prompts share stdout, and --json is refused).
NO_NUMBERS = {("demo",)}


def test_every_command_that_computes_numbers_has_json():
    without = [" ".join(path) for path, leaf in subcommands()
               if option(leaf, "--json") is None and path not in NO_NUMBERS]
    assert without == []


def test_psf_json_is_the_record_of_what_it_printed(capsys, tmp_path):
    code, out, _ = run(capsys, "psf", "--rx", "-1", "--pupil-mm", "3", "--size", "33", "-o", tmp_path / "p.exr", "--json")
    assert code == 0
    record = json.loads(out)
    assert record["size_px"] == [33, 33] and record["pupil_diameter_mm"] == 3.0 and 0 < record["energy_in_field"] <= 1
    assert record["written"] == [str(tmp_path / "p.exr")] and '"psf"' in json.dumps(record["provenance"])


def test_blur_json_names_the_file_and_the_sampling(capsys, tmp_path):
    assert main(["chart", "--logmar", "1", "-o", str(tmp_path / "c.exr")]) == 0
    capsys.readouterr()
    code, out, _ = run(capsys, "blur", tmp_path / "c.exr", "--rx", "-0.5", "--pupil-mm", "3", "-o", tmp_path / "b.exr", "--json")
    record = json.loads(out)
    assert code == 0 and record["arcmin_per_px"] == 1.0 and record["written"] == [str(tmp_path / "b.exr")]
    assert record["size_px"] == [150, 550] and '"blur"' in json.dumps(record["provenance"])


def test_chart_json_names_its_files_and_letters(capsys, tmp_path):
    code, out, _ = run(capsys, "chart", "--logmar", "1", "--letters", "NCKZO", "-o", tmp_path / "c.exr", "--json")
    record = json.loads(out)
    assert code == 0 and record["kind"] == "chart" and record["size_px"] == [150, 550]
    assert record["letters"] == list("NCKZO") and record["arcmin_per_px"] == 1.0
    assert record["written"][0] == str(tmp_path / "c.exr") and record["written"][-1].endswith(".letters.json")
    assert all(Path(p).is_file() for p in record["written"]) and '"vissim chart"' in json.dumps(record["provenance"])


def test_population_json_is_the_record_of_what_it_printed(capsys, tmp_path):
    code, out, _ = run(capsys, "population", "jaeken-artal-2012", "--subjects", "1", "--pupil-mm", "3",
                       "--mtf-cyc-per-deg", "10", "-o", tmp_path / "run", "--json")
    record = json.loads(out)
    assert code == 0 and record["eyes"] == ["jaeken-artal-2012:1:right", "jaeken-artal-2012:1:left"]
    assert [c["eyes_evaluated"] for c in record["conditions"]] == [2] and record["mtf_cyc_per_deg"] == [10.0]
    assert str(tmp_path / "run" / "eyes.csv") in record["written"] and record["provenance"]["inputs"]["command"] == "population"


def test_atv_json_is_the_record_of_what_it_printed(capsys, tmp_path):
    code, out, _ = run(capsys, "atv", "simulate", "--rx", "-1", "--pupil-mm", "4", "--lenses", "-2,-1,0,1,2",
                       "-o", tmp_path / "sim", "--json")
    record = json.loads(out)
    assert code == 0 and [t["trial_lens_diopters"] for t in record["experiment"]["trials"]] == [-2, -1, 0, 1, 2]
    assert record["analyses"] and all(Path(p).exists() for p in record["written"])
    code, out, _ = run(capsys, "atv", "run", "-o", tmp_path / "run.json", "--json")
    record = json.loads(out)
    assert code == 0 and record["observer"]["kind"] == "simulated" and record["written"] == [str(tmp_path / "run.json")]
    assert record["result"] == json.loads((tmp_path / "run.json").read_text())["result"]
    code, out, _ = run(capsys, "atv", "analyze", ROOT / "validation" / "atv", "-o", tmp_path / "analysis", "--json")
    record = json.loads(out)
    assert code == 0 and {a["condition"] for a in record["analyses"]} == {"with_drops", "without_drops"}
    assert all(Path(p).is_file() for p in record["written"])
    code, out, err = run(capsys, "atv", "run", "--observer", "person", "-o", tmp_path / "p.json", "--json")
    assert code == 2 and err.count("\n") == 1 and "--json goes with --observer simulated" in err


@pytest.mark.parametrize("table, says", [
    ("[chart]\ndistance_mm = 914.4\n", "[chart]: 'distance_mm' is now 'chart_distance_m' (metres, not mm)"),
    ("[holder]\ndistance_mm = 10.0\n", "[holder]: 'distance_mm' is now 'vertex_distance_mm'"),
])
def test_a_renamed_scene_key_is_refused_naming_its_tables_new_key(tmp_path, table, says):
    from vissim.bench.dslr.scene_files import load_bench_toml

    path = tmp_path / "old.toml"
    path.write_text(table, encoding="utf-8")
    with pytest.raises(VissimInputError) as caught:
        load_bench_toml(path)
    assert says in str(caught.value) and "\n" not in str(caught.value)


def test_the_chart_distance_is_one_spelling_in_every_scene_and_flag():
    from vissim.bench.dslr.scene_files import load_bench_toml
    from vissim.thesis import THESIS_CHART_DISTANCE_MM

    bench, spec = load_bench_toml(ROOT / "scenes" / "dslr_bench.toml")
    assert bench.chart_distance_mm == THESIS_CHART_DISTANCE_MM and spec.viewing_distance_m == pytest.approx(0.9144)
    eye = tomllib.loads((ROOT / "scenes" / "eye.toml").read_text(encoding="utf-8"))
    assert eye["chart"]["chart_distance_m"] == 6.0
    assert {" ".join(p) for p, leaf in subcommands() if option(leaf, "--chart-distance-m")} == {"chart", "render eye"}


def test_a_count_agrees_with_its_noun():
    from vissim.checks import counted

    assert (counted(1, "ray"), counted(0, "ray"), counted(4, "ray")) == ("1 ray", "0 rays", "4 rays")
    assert counted(2, "axis", "axes") == "2 axes"


def test_no_message_writes_a_noun_as_singular_or_plural():
    # "4 ray(s) miss" reads as code: a count's noun follows the count (vissim.checks.counted).
    import re

    hedged = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
              for path in sorted((ROOT / "vissim").rglob("*.py"))
              for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
              if re.search(r"(Error|error)\(.*\w\(s\)", line) or re.search(r"^\s*f?\".*\{[^}]*\}[^\"]*\w\(s\) ", line)]
    assert hedged == []


# -- the vocabulary's defaults and limits name constants: each exists and holds the number the text states ----------
_CONSTANT_MODULES = ("vissim.checks", "vissim.thesis", "vissim.optics.eyes.defaults", "vissim.optics.rx.conventions")
_NUMBER = r"(-?\d+(?:\.\d+)?)"
_UNIT_WORD = r"(?: (?:D|mm|m|nm|deg))?"  # "±30 D (TRIAL_LENS_RANGE_DIOPTERS)"


def _constant(name: str):
    for module in _CONSTANT_MODULES:
        value = getattr(importlib.import_module(module), name, None)
        if value is not None:
            return value
    raise AssertionError(f"the vocabulary names {name}, which none of {', '.join(_CONSTANT_MODULES)} defines")


def _in_concept_unit(value: float, name: str, unit: str) -> float:
    """A constant in its name's unit, in the concept's first unit: a length in mm where the concept's is metres."""
    concept_in_metres = unit == "m" or unit.startswith("m ")
    return mm_to_m(value) if name.endswith("_MM") and concept_in_metres else value


@pytest.mark.parametrize("concept", CONCEPTS, ids=lambda c: c.name)
def test_each_constant_the_vocabulary_names_holds_the_number_it_states(concept):
    """A default or limit written as ``550 (DEFAULT_WAVELENGTH_NM)`` or ``0-200 (VERTEX_DISTANCE_RANGE_MM)``: the
    constant exists, and holds that number or range (in the concept's unit); a bare name need only exist."""
    for text in (concept.default, concept.limit):
        for name in re.findall(r"\b[A-Z][A-Z0-9]*(?:_[A-Z0-9]+)+\b", text):
            _constant(name)
        for low, high, name in re.findall(_NUMBER + r"-" + _NUMBER + _UNIT_WORD + r" \(([A-Z_0-9]+)\)", text):
            value = tuple(_in_concept_unit(float(v), name, concept.unit) for v in _constant(name))
            assert value == (float(low), float(high)), (concept.name, name, value)
        for plus_minus, single, name in re.findall(r"(±)?(?<![\d.-])" + _NUMBER + _UNIT_WORD + r" \(([A-Z_0-9]+)\)",
                                                   text):
            value = _constant(name)
            expected = (-float(single), float(single)) if plus_minus else float(single)
            got = tuple(_in_concept_unit(float(v), name, concept.unit) for v in value) if plus_minus else \
                _in_concept_unit(float(value), name, concept.unit)
            assert got == expected, (concept.name, name, got)
