"""Recordings from someone else's writer: every odd-but-valid form ``docs/recording-format.md`` allows is read,
and gives the verdicts (and figures) of the plain recording wherever the change carries no information.

Each variant is a copy of a real recording (``tests/data/recordings``, written by PrintWatch's simulator and
demo; see ``tests/data/SOURCES.md``) rewritten the way another program could have written it.
"""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from octoprint_printwatch.cli import main
from octoprint_printwatch.core.errors import RecordingError
from octoprint_printwatch.core.pipeline import evaluate_recording
from octoprint_printwatch.core.recording import load_recording

RECORDINGS = Path(__file__).resolve().parents[1] / "data" / "recordings"
#: model only, two cameras, no pair; the part is knocked off at layer 24, and the checks at layers 24 (loose
#: material at its foot, seen from two sides) and 32 (material missing in both views) fail
GEAR = "gear_detached_two_views"
#: G-code only (PrusaSlicer), a stereo pair, layer_height given; a normal print
CUBE = "cube_jpeg_top_sliver"


# ------------------------------------------------------------------ helpers
def copy_of(name: str, tmp_path: Path) -> Path:
    target = tmp_path / name
    shutil.copytree(RECORDINGS / name, target)
    return target


def session(rec: Path) -> dict:
    return json.loads((rec / "session.json").read_text(encoding="utf-8"))


def save(rec: Path, doc: dict) -> None:
    (rec / "session.json").write_text(json.dumps(doc, indent=1), encoding="utf-8")


def frame_entries(doc: dict):
    """(owner dict, camera, relative path) of every background and check frame."""
    for cam, rel in doc.get("background", {}).items():
        yield doc["background"], cam, rel
    for check in doc["checks"]:
        for cam, rel in check.get("frames", {}).items():
            yield check["frames"], cam, rel


def rewrite_frames(rec: Path, convert, suffix: str, every: int = 1) -> None:
    """Re-encode every ``every``-th frame with ``convert(image) -> array to write`` as ``suffix``."""
    doc = session(rec)
    for i, (owner, cam, rel) in enumerate(list(frame_entries(doc))):
        if i % every:
            continue
        old = rec / rel
        image = cv2.imread(str(old), cv2.IMREAD_COLOR)
        new_rel = str(Path(rel).with_suffix(suffix))
        assert cv2.imwrite(str(rec / new_rel), convert(image))
        if new_rel != rel:
            old.unlink()
        owner[cam] = new_rel
    save(rec, doc)


def evaluate(rec: Path) -> dict:
    return evaluate_recording(load_recording(rec))


def figures(doc: dict, rename: dict | None = None) -> list:
    """Per check (in layer order): layer, verdict, shape error per camera, size figures per pair."""
    rename = rename or {}
    out = []
    for check in sorted(doc["checks"], key=lambda c: (c["z"], c["layer"])):
        shape = {rename.get(cam, cam): pct for cam, pct in check["shape_error_pct"].items()}
        size = {}
        for key, entry in check["size"].items():
            left, right = key.split("+") if key.count("+") == 1 else (key, "")
            size[f"{rename.get(left, left)}+{rename.get(right, right)}"] = (
                entry.get("width_mm"), entry.get("height_mm"), entry.get("error_pct"))
        out.append((check["layer"], check["verdict"], shape, size))
    return out


def assert_close(got: list, want: list, tol: float = 0.0) -> None:
    assert [(c[0], c[1]) for c in got] == [(c[0], c[1]) for c in want]
    for g, w in zip(got, want):
        assert g[2].keys() == w[2].keys() and g[3].keys() == w[3].keys()
        for cam in w[2]:
            if w[2][cam] is None or g[2][cam] is None:
                assert g[2][cam] is None and w[2][cam] is None, (g, w)
            else:
                assert abs(g[2][cam] - w[2][cam]) <= tol, (cam, g, w)
        if tol == 0.0:
            assert g[3] == w[3]


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    """The plain recordings' figures (the reference every variant is compared with)."""
    base = tmp_path_factory.mktemp("plain")
    return {name: figures(evaluate(copy_of(name, base))) for name in (GEAR, CUBE)}


def test_the_plain_recordings_are_what_the_variants_need(plain):
    # the comparisons below mean something only if the reference has a failure and numbers to compare
    assert [c[1] for c in plain[GEAR]] == ["ok", "fail", "fail"]
    assert all(pct > 0 for pct in plain[GEAR][1][2].values())
    assert [c[1] for c in plain[CUBE]] == ["ok", "ok", "ok"]
    assert any(size[0] is not None for c in plain[CUBE] for size in c[3].values())


# ------------------------------------------------------- the expected part
def placed_cube_model(rec: Path) -> str:
    """The library cube's STL (the part the recording's G-code was sliced from) moved where PrusaSlicer put
    it, as ``model.stl``."""
    import octoprint_printwatch
    from octoprint_printwatch.core.geometry import place_mesh_on_gcode

    library_cube = Path(octoprint_printwatch.__file__).parent / "data" / "parts" / "cube.stl"
    placement = place_mesh_on_gcode(str(library_cube), rec / "print.gcode")
    placement.mesh.export(rec / "model.stl")
    return "model.stl"


@pytest.mark.parametrize("keep_gcode", [True, False], ids=["model_and_gcode", "model_only"])
def test_a_model_where_the_slicer_put_it_gives_the_gcodes_verdicts(plain, tmp_path, keep_gcode):
    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    doc["model"] = placed_cube_model(rec)
    if not keep_gcode:
        del doc["gcode"]
        (rec / "print.gcode").unlink()
    save(rec, doc)
    got = figures(evaluate(rec))
    assert [c[1] for c in got] == [c[1] for c in plain[CUBE]]


def test_a_model_with_holes_beside_the_gcode_gives_way_to_the_gcode(plain, tmp_path):
    # an exporter that leaves holes: the mesh cannot be made a solid; the G-code says what is printed
    import trimesh

    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    doc["model"] = placed_cube_model(rec)
    mesh = trimesh.load(rec / "model.stl", force="mesh").subdivide().subdivide()
    holes = np.ones(len(mesh.faces), bool)
    holes[::7] = False
    trimesh.Trimesh(mesh.vertices, mesh.faces[holes], process=False).export(rec / "model.stl")
    save(rec, doc)
    got = evaluate(rec)
    assert any("G-code" in note for note in got["notes"])
    assert [c[1] for c in figures(got)] == [c[1] for c in plain[CUBE]]


@pytest.mark.parametrize("layer_height", [None, 0.3, 0.1])
def test_layer_height_absent_or_unlike_the_gcode_changes_nothing(plain, tmp_path, layer_height):
    # each check's z says what should be there: layer_height is informative only
    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    doc.pop("layer_height")
    if layer_height is not None:
        doc["layer_height"] = layer_height
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[CUBE])


def test_windows_line_endings_in_the_gcode(plain, tmp_path):
    rec = copy_of(CUBE, tmp_path)
    text = (rec / "print.gcode").read_bytes()
    assert b"\r\n" not in text
    (rec / "print.gcode").write_bytes(text.replace(b"\n", b"\r\n"))
    assert_close(figures(evaluate(rec)), plain[CUBE])


def test_ascii_stl_reads_as_the_binary_one(plain, tmp_path):
    import trimesh

    rec = copy_of(GEAR, tmp_path)
    mesh = trimesh.load(rec / "model.stl", force="mesh")
    assert (rec / "model.stl").read_bytes()[:5] != b"solid"   # binary to start with
    (rec / "model.stl").write_bytes(trimesh.exchange.stl.export_stl_ascii(mesh).encode())
    assert_close(figures(evaluate(rec)), plain[GEAR], tol=0.01)


# ------------------------------------------------------------------ frames
def test_png_and_jpeg_frames_mixed(plain, tmp_path):
    rec = copy_of(GEAR, tmp_path)
    rewrite_frames(rec, lambda image: image, ".png", every=2)   # lossless: the same decoded pixels
    doc = session(rec)
    suffixes = {Path(rel).suffix for _, _, rel in frame_entries(doc)}
    assert suffixes == {".png", ".jpg"}
    assert_close(figures(evaluate(rec)), plain[GEAR])


@pytest.mark.parametrize("form", ["alpha", "16bit", "upper-case suffix"])
def test_png_forms_decode_to_the_same_colour_frame(plain, tmp_path, form):
    rec = copy_of(GEAR, tmp_path)
    if form == "alpha":
        rewrite_frames(rec, lambda im: np.dstack([im, np.full(im.shape[:2], 255, np.uint8)]), ".png")
    elif form == "16bit":
        rewrite_frames(rec, lambda im: im.astype(np.uint16) * 257, ".png")
    else:
        rewrite_frames(rec, lambda im: im, ".PNG")
    assert_close(figures(evaluate(rec)), plain[GEAR])


def test_frame_files_are_told_apart_by_content_not_name(plain, tmp_path):
    # a PNG named .jpg, JPEGs named .jpeg or with no suffix at all: the bytes say what they are
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    for i, (owner, cam, rel) in enumerate(list(frame_entries(doc))):
        new_rel = [rel[:-4], rel[:-4] + ".jpeg", rel[:-4] + ".frame"][i % 3]
        (rec / rel).rename(rec / new_rel)
        owner[cam] = new_rel
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[GEAR])
    mislabelled = copy_of(GEAR, tmp_path / "png")
    rewrite_frames(mislabelled, lambda im: im, ".png")
    doc = session(mislabelled)
    for owner, cam, rel in list(frame_entries(doc)):
        owner[cam] = rel[:-4] + ".jpg"
        (mislabelled / rel).rename(mislabelled / owner[cam])
    save(mislabelled, doc)
    assert_close(figures(evaluate(mislabelled)), plain[GEAR])


def test_grayscale_frames_are_read_as_colour(plain, tmp_path):
    # a one-channel PNG gives exactly the frames of a colour PNG of the same grey pixels
    grey = copy_of(GEAR, tmp_path / "grey")
    rewrite_frames(grey, lambda im: cv2.cvtColor(im, cv2.COLOR_BGR2GRAY), ".png")
    grey3 = copy_of(GEAR, tmp_path / "grey3")
    rewrite_frames(grey3, lambda im: cv2.cvtColor(cv2.cvtColor(im, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR), ".png")
    rec = load_recording(grey)
    assert rec.read_frame(rec.checks[0], "cam1").shape == (480, 640, 3)
    assert_close(figures(evaluate(grey)), figures(evaluate(grey3)))
    # and a grayscale JPEG is read (its verdicts need not be the colour ones: colour is information)
    jpeg = copy_of(GEAR, tmp_path / "jpeg")
    rewrite_frames(jpeg, lambda im: cv2.cvtColor(im, cv2.COLOR_BGR2GRAY), ".jpg")
    assert len(evaluate(jpeg)["checks"]) == 3


def test_frames_at_twice_the_calibrated_resolution(plain, tmp_path):
    # the same picture at another resolution: K is scaled to it (the shape check runs at a working size)
    rec = copy_of(GEAR, tmp_path)
    # (each pixel a 2x2 block, which the shrink back to the working size averages to the pixel again)
    rewrite_frames(rec, lambda im: cv2.resize(im, None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST), ".png")
    assert load_recording(rec).read_background("cam1").shape == (960, 1280, 3)
    assert_close(figures(evaluate(rec)), plain[GEAR])


def test_calibrated_at_twice_the_frame_resolution(plain, tmp_path):
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    for cam in doc["cameras"].values():
        cam["width"], cam["height"] = 2 * cam["width"], 2 * cam["height"]
        cam["K"] = [[2 * k for k in cam["K"][0]], [2 * k for k in cam["K"][1]], cam["K"][2]]
        cam["K"][0][2] += 0.5    # pixel centres: x_full = 2 x + 0.5
        cam["K"][1][2] += 0.5
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[GEAR], tol=0.5)


def test_no_width_and_height_means_the_frames_size(plain, tmp_path):
    # K is in the pixels of the frames the camera gives: a writer that leaves the size out loses nothing
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    for cam in doc["cameras"].values():
        del cam["width"], cam["height"]
    save(rec, doc)
    loaded = load_recording(rec)
    assert loaded.cameras["cam1"].size == (640, 480) and len(loaded.notes) == 2
    assert_close(figures(evaluate(rec)), plain[GEAR])


def test_a_principal_point_outside_the_stated_size_is_noted(tmp_path):
    # width/height written for one resolution, K calibrated at another: the user is told which numbers disagree
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    doc["cameras"]["cam2"]["width"], doc["cameras"]["cam2"]["height"] = 320, 240
    save(rec, doc)
    notes = load_recording(rec).notes
    assert len(notes) == 1 and "cam2" in notes[0] and "principal point" in notes[0]


def test_frames_of_another_aspect_ratio_are_no_evidence_and_say_why(tmp_path):
    # 16:9 frames against a 4:3 calibration: no resize maps one onto the other (another crop of the sensor)
    rec = copy_of(GEAR, tmp_path)
    rewrite_frames(rec, lambda im: cv2.resize(im, (1280, 720)), ".png")
    doc = evaluate(rec)
    for check in doc["checks"]:
        assert check["verdict"] == "unknown"
        assert all(pct is None for pct in check["shape_error_pct"].values())
        assert any("aspect ratio" in reason for reason in check["reasons"])


# ----------------------------------------------------------------- cameras
@pytest.mark.parametrize("form", ["4", "8", "12", "14", "nested (1, 5)"])
def test_every_distortion_vector_length_opencv_returns(plain, tmp_path, form):
    # the recordings' k3 is 0: the 4-coefficient form and the zero-padded longer ones are the same lens
    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    for cam in doc["cameras"].values():
        assert cam["dist"][4] == 0.0
        if form == "nested (1, 5)":
            cam["dist"] = [cam["dist"]]
        else:
            n = int(form)
            cam["dist"] = (cam["dist"] + [0.0] * 14)[:n]
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[CUBE])


@pytest.mark.parametrize("form", ["absent", "empty", "null"])
def test_no_distortion_given_means_none(tmp_path, form):
    rec = copy_of(CUBE, tmp_path / "zero")
    doc = session(rec)
    for cam in doc["cameras"].values():
        cam["dist"] = [0.0] * 5
    save(rec, doc)
    want = figures(evaluate(rec))
    rec = copy_of(CUBE, tmp_path / form)
    doc = session(rec)
    for cam in doc["cameras"].values():
        if form == "absent":
            del cam["dist"]
        else:
            cam["dist"] = [] if form == "empty" else None
    save(rec, doc)
    assert_close(figures(evaluate(rec)), want)


def test_opencv_shaped_arrays_and_float_sizes(plain, tmp_path):
    # K flat, rvec/tvec as the (3, 1) arrays cv2 returns, sizes written as floats by a JSON library
    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    for cam in doc["cameras"].values():
        cam["K"] = [k for row in cam["K"] for k in row]
        cam["rvec"] = [[v] for v in cam["rvec"]]
        cam["tvec"] = [[v] for v in cam["tvec"]]
        cam["width"], cam["height"] = float(cam["width"]), float(cam["height"])
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[CUBE])


def test_camera_names_with_spaces_dots_plus_and_slash(plain, tmp_path):
    rename = {"cam0L": "usb/1 left cam.v2", "cam0R": "right+cam (usb 1.1)"}
    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    doc["cameras"] = {rename[n]: c for n, c in doc["cameras"].items()}
    doc["pairs"] = [[rename[n] for n in pair] for pair in doc["pairs"]]
    doc["background"] = {rename[n]: rel for n, rel in doc["background"].items()}
    for check in doc["checks"]:
        check["frames"] = {rename[n]: rel for n, rel in check["frames"].items()}
    save(rec, doc)
    out = tmp_path / "overlays"
    got = evaluate_recording(load_recording(rec), overlay_dir=out)
    assert set(got["checks"][0]["size"]) == {"usb/1 left cam.v2+right+cam (usb 1.1)"}
    back = {new: old for old, new in rename.items()}
    got_figures = [(c[0], c[1], {back[k]: v for k, v in c[2].items()}, {"cam0L+cam0R": s for s in c[3].values()})
                   for c in figures(got)]
    assert_close(got_figures, plain[CUBE])
    assert len(list(out.glob("*.jpg"))) == 6    # one overlay per camera per check, in the folder asked for


def test_right_camera_listed_first_and_a_camera_in_no_pair(plain, tmp_path):
    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    doc["cameras"] = dict(reversed(list(doc["cameras"].items())))
    assert list(doc["cameras"]) == ["cam0R", "cam0L"]
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[CUBE])
    # without the pair both cameras still run their shape checks
    doc["pairs"] = []
    save(rec, doc)
    got = figures(evaluate(rec))
    assert [(c[0], c[1], c[2]) for c in got] == [(c[0], c[1], c[2]) for c in plain[CUBE]]
    assert all(c[3] == {} for c in got)


def test_frames_and_backgrounds_of_an_uncalibrated_camera_are_ignored(plain, tmp_path):
    # an overview webcam recorded but never calibrated: nothing to compare it with, no reason to refuse
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    doc["background"]["overview"] = doc["background"]["cam1"]
    for check in doc["checks"]:
        check["frames"]["overview"] = check["frames"]["cam1"]
    save(rec, doc)
    got = evaluate(rec)
    assert_close(figures(got), plain[GEAR])
    assert any("overview" in note for note in got["notes"])


# ------------------------------------------------------------------ checks
def test_checks_not_in_layer_order(plain, tmp_path):
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    doc["checks"] = [doc["checks"][i] for i in (2, 0, 1)]
    save(rec, doc)
    got = evaluate(rec)
    assert [c["layer"] for c in got["checks"]] == [8, 24, 32]
    assert got["first_failure_layer"] == 24
    assert_close(figures(got), plain[GEAR])


def test_integer_z_and_integral_float_layer(plain, tmp_path):
    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    for check in doc["checks"]:
        assert check["z"] == int(check["z"])
        check["z"] = int(check["z"])
        check["layer"] = float(check["layer"])     # 25.0: what a writer whose numbers are all doubles writes
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[CUBE])


def test_a_check_missing_one_cameras_frame(plain, tmp_path):
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    del doc["checks"][1]["frames"]["cam1"]
    save(rec, doc)
    got = evaluate(rec)
    middle = got["checks"][1]
    assert middle["shape_error_pct"]["cam1"] is None
    # cam1 only abstains; cam2 alone sees the material the knock left around the part's foot
    assert middle["verdict"] == "fail" and any("material appeared around the part" in r and "cam2" in r
                                               for r in middle["reasons"])
    assert any(reason.startswith("cam1: no frame") for reason in middle["reasons"])
    assert middle["shape_error_pct"]["cam2"] == plain[GEAR][1][2]["cam2"]
    assert got["checks"][0]["verdict"] == "ok" and got["checks"][2]["verdict"] == "fail"


@pytest.mark.parametrize("form", ["absent", "null"])
def test_a_camera_without_background_is_no_evidence_not_an_error(plain, tmp_path, form):
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    (rec / doc["background"].pop("cam2")).unlink()
    if form == "null":
        doc["background"]["cam2"] = None
    save(rec, doc)
    got = evaluate(rec)
    for check in got["checks"]:
        assert check["shape_error_pct"]["cam2"] is None
        assert any("cam2: no background" in reason for reason in check["reasons"])
    # cam1 alone sees what it saw beside cam2 while nothing failed (the failing check's verdict is the
    # decision rules' business: one camera missing material uncorroborated is judged differently)
    assert [c["shape_error_pct"]["cam1"] for c in got["checks"][:2]] == [c[2]["cam1"] for c in plain[GEAR][:2]]


# ------------------------------------------------------- files and paths
def test_unknown_keys_everywhere_are_ignored(plain, tmp_path):
    rec = copy_of(CUBE, tmp_path)
    doc = session(rec)
    doc["writer"] = {"name": "another-program", "version": [3, 1]}
    doc["truth"] = None
    for cam in doc["cameras"].values():
        cam["serial"] = "0001"
        cam["reprojection_error_px"] = 0.31
    for i, check in enumerate(doc["checks"]):
        check["timestamp"] = f"2026-11-22T10:0{i}:00Z"
        check["temperatures"] = {"tool0": 210.0}
    doc["pairs_note"] = [["x", "y"]]
    save(rec, doc)
    (rec / "notes.txt").write_text("written by another program\n")
    assert_close(figures(evaluate(rec)), plain[CUBE])


def test_paths_with_subfolders_and_dot_slash(plain, tmp_path):
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    for owner, cam, rel in list(frame_entries(doc)):
        new_rel = f"./frames/by camera/{cam}/{Path(rel).parent.name}_{Path(rel).name}"
        (rec / new_rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.move(rec / rel, rec / new_rel)
        owner[cam] = new_rel
    (rec / "part").mkdir()
    shutil.move(rec / "model.stl", rec / "part" / "gear.stl")
    doc["model"] = "./part/gear.stl"
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[GEAR])


def test_windows_separators_in_paths(plain, tmp_path):
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    for owner, cam, rel in list(frame_entries(doc)):
        owner[cam] = rel.replace("/", "\\")
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[GEAR])


@pytest.mark.parametrize("where", ["/home/someone/prints/rec_0042", "C:\\Users\\someone\\rec_0042", ""])
def test_absolute_paths_from_where_the_recording_was_written(plain, tmp_path, where):
    # written with absolute paths, then moved (or "/checks/...": rooted at the recording folder)
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    sep = "\\" if where.startswith("C:") else "/"
    for owner, cam, rel in list(frame_entries(doc)):
        owner[cam] = where + sep + rel.replace("/", sep)
    doc["model"] = where + sep + "model.stl"
    save(rec, doc)
    assert_close(figures(evaluate(rec)), plain[GEAR])


def test_an_absolute_path_outside_the_folder_is_still_refused(tmp_path):
    rec = copy_of(GEAR, tmp_path)
    outside = tmp_path / "elsewhere.stl"
    shutil.copy(rec / "model.stl", outside)
    doc = session(rec)
    doc["model"] = str(outside)
    save(rec, doc)
    with pytest.raises(RecordingError, match="outside the recording folder"):
        load_recording(rec)


def test_session_json_with_a_byte_order_mark_and_crlf(plain, tmp_path):
    rec = copy_of(GEAR, tmp_path)
    text = json.dumps(session(rec), indent=2).replace("\n", "\r\n")
    (rec / "session.json").write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))
    assert_close(figures(evaluate(rec)), plain[GEAR])


def test_units_other_than_mm_are_refused_in_one_line(tmp_path):
    rec = copy_of(GEAR, tmp_path)
    doc = session(rec)
    doc["units"] = "inch"
    save(rec, doc)
    with pytest.raises(RecordingError, match="units must be 'mm'") as info:
        load_recording(rec)
    assert "\n" not in str(info.value) and "session.json" in str(info.value)
    assert main(["evaluate", str(rec), "--json", str(tmp_path / "out.json")]) == 2
    assert not (tmp_path / "out.json").exists()


def test_the_cli_reads_an_odd_recording_and_exits_0(plain, tmp_path):
    rec = copy_of(GEAR, tmp_path)
    rewrite_frames(rec, lambda im: np.dstack([im, np.full(im.shape[:2], 255, np.uint8)]), ".png", every=2)
    doc = session(rec)
    doc["checks"].reverse()
    doc["extra"] = {"by": "another writer"}
    text = json.dumps(doc).encode("utf-8")
    (rec / "session.json").write_bytes(b"\xef\xbb\xbf" + text)
    out = tmp_path / "out.json"
    assert main(["evaluate", str(rec), "--json", str(out)]) == 0
    got = json.loads(out.read_text())
    assert got["first_failure_layer"] == 24
    assert_close(figures(got), plain[GEAR])


# ------------------------------------------------- slicers' G-code alone
@pytest.mark.slow
@pytest.mark.parametrize("gcode", ["cura413_ender3_sun_gear.gcode", "prusa25_sun_gear_zhop_relative_e.gcode"])
def test_a_slicers_gcode_alone_gives_the_models_verdicts(tmp_path, gcode_dir, gcode):
    """A runout printed from Cura's / PrusaSlicer's G-code, rendered by PrintWatch's simulator from the sun gear
    STL placed where the slicer put it: the G-code alone and the model alone see the same failure."""
    from octoprint_printwatch.core.geometry import place_mesh_on_gcode
    from octoprint_printwatch.simulator.recording import write_recording
    from octoprint_printwatch.simulator.rig import make_rig
    from octoprint_printwatch.simulator.scenario import Scenario
    from octoprint_printwatch.simulator.scene import PrintSimulator

    placement = place_mesh_on_gcode(str(gcode_dir / "sun_gear.stl"), gcode_dir / gcode)
    sim = PrintSimulator(placement.mesh, make_rig("ring", n_cameras=2, seed=3), "seed",
                         Scenario("runout", onset_layer=60), seed=3)
    rec = tmp_path / "rec"
    write_recording(rec, sim, every_n_layers=40)
    shutil.copy(gcode_dir / gcode, rec / "print.gcode")
    verdicts = {}
    for given in ("model", "gcode"):
        doc = session(rec)
        doc.pop("model", None)
        doc.pop("gcode", None)
        doc[given] = "model.stl" if given == "model" else "print.gcode"
        save(rec, doc)
        verdicts[given] = figures(evaluate(rec))
    assert_close(verdicts["gcode"], verdicts["model"], tol=1.0)
    truth = json.loads((rec / "truth.json").read_text())["checks"]
    assert [c[1] for c in verdicts["gcode"]] == ["fail" if t["should_flag"] else "ok" for t in truth]
