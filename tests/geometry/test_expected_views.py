"""Expected silhouettes, depth maps and layer bands against shapes whose images are known."""
import cv2
import numpy as np
import pytest
import trimesh

from octoprint_printwatch.core import render
from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.geometry import part_from_mesh, place_mesh_on_gcode
from octoprint_printwatch.core.render import render_expected_views, render_silhouette, render_view

CENTRE = np.array([100.0, 100.0, 0.0])


def oblique_camera(dist=None, name="cam") -> Camera:
    return Camera.look_at(name, (230.0, 10.0, 110.0), (100.0, 100.0, 15.0), focal_px=760.0, dist=dist)


def analytic_outline(points_3d: np.ndarray, camera: Camera, distorted: bool) -> np.ndarray:
    """Silhouette of a convex solid = convex hull of its (densely sampled) projected surface points."""
    uv = camera.project(points_3d, distorted=distorted)
    mask = np.zeros((camera.height, camera.width), np.uint8)
    hull = cv2.convexHull(uv.astype(np.float32))
    cv2.fillConvexPoly(mask, np.round(hull.reshape(-1, 2) * 16).astype(np.int32), 1, shift=4)
    return mask.astype(bool), float(cv2.contourArea(hull)), float(cv2.arcLength(hull, True))


def dense_box_points(lo, hi, n=60) -> np.ndarray:
    """Points on the 12 edges of a box, n per edge (distortion bends them)."""
    t = np.linspace(0.0, 1.0, n)[:, None]
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    segments = [(a, b) for i, a in enumerate(corners) for b in corners[i + 1:]
                if np.count_nonzero(a != b) == 1]
    return np.concatenate([a + (b - a) * t for a, b in segments])


def bbox(mask: np.ndarray) -> np.ndarray:
    ys, xs = np.nonzero(mask)
    return np.array([xs.min(), xs.max(), ys.min(), ys.max()], float)


def shapes():
    cube = trimesh.creation.box((30, 30, 30))
    cube.apply_translation(CENTRE + (0, 0, 15))
    cylinder = trimesh.creation.cylinder(radius=14.0, height=48.0, sections=256)
    cylinder.apply_translation(CENTRE + (0, 0, 24))
    pyramid = trimesh.creation.cone(radius=1.0, height=33.0, sections=4)  # square pyramid, apex up
    pyramid.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 4, (0, 0, 1)))  # sides along x, y
    pyramid.vertices[:, :2] *= 15.0 * np.sqrt(2)
    pyramid.apply_translation(CENTRE)
    theta = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    circle = np.column_stack([14 * np.cos(theta), 14 * np.sin(theta)])
    return {
        "cube": (cube, dense_box_points(CENTRE + (-15, -15, 0), CENTRE + (15, 15, 30))),
        "cylinder": (cylinder, np.concatenate([np.column_stack([circle + CENTRE[:2], np.full(720, z)]) for z in (0.0, 48.0)])),
        "pyramid": (pyramid, np.concatenate([pyramid.vertices, dense_box_points(CENTRE + (-15, -15, 0), CENTRE + (15, 15, 0))])),
    }


@pytest.mark.parametrize("shape", ["cube", "cylinder", "pyramid"])
@pytest.mark.parametrize("distorted", [False, True])
def test_silhouette_of_analytic_shapes_matches_area_and_bbox_within_1_percent(shape, distorted):
    mesh, surface = shapes()[shape]
    camera = oblique_camera(dist=[-0.25, 0.08, 0.0, 0.0, 0.0] if distorted else None)
    mask = render_silhouette(mesh, camera, distorted=distorted)
    # Barrel distortion bows straight edges outwards: these convex outlines stay convex.
    expected, area, perimeter = analytic_outline(surface, camera, distorted)
    assert mask.sum() == pytest.approx(area, rel=0.01)
    size = bbox(expected)[[1, 3]] - bbox(expected)[[0, 2]]
    assert np.all(np.abs(bbox(mask) - bbox(expected)) <= np.maximum(0.01 * size[[0, 0, 1, 1]], 1.0))
    assert np.count_nonzero(mask ^ expected) < perimeter  # at most the boundary pixels differ


def test_distorted_silhouette_is_the_undistorted_one_seen_through_the_lens():
    mesh, _ = shapes()["cylinder"]
    # The part off-centre, where the lens bends most.
    camera = Camera.look_at("corner", (230.0, 10.0, 110.0), (60.0, 150.0, -10.0), focal_px=760.0,
                            dist=[-0.3, 0.1, 0.001, -0.001, 0.0])
    distorted = render_silhouette(mesh, camera, distorted=True)
    undistorted = render_silhouette(mesh, camera, distorted=False)
    lens_effect = np.count_nonzero(distorted ^ undistorted)
    assert lens_effect > 0.01 * undistorted.sum()  # the lens matters here
    back = camera.undistort_image(distorted.astype(np.uint8) * 255, interpolation=cv2.INTER_NEAREST) > 127
    assert np.count_nonzero(back ^ undistorted) < 0.3 * lens_effect


def test_partial_solid_silhouette_grows_with_height_and_top_view_sees_the_section():
    part = part_from_mesh(shapes()["pyramid"][0])
    side = oblique_camera()
    areas = [render_silhouette(part, side, z=z).sum() for z in (2.0, 10.0, 20.0, 33.0)]
    assert areas == sorted(areas) and areas[0] > 0
    top = Camera.look_at("top", (100.0, 100.0, 300.0), (100.0, 100.0, 0.0), focal_px=800.0, up=(0, 1, 0))
    # Straight down: the silhouette is the footprint, 30 x 30 mm at 300 mm -> 80 px square.
    assert render_silhouette(part, top, z=5.0).sum() == pytest.approx(80.0 * 80.0, rel=0.01)


def test_depth_map_of_a_face_on_cube_is_the_distance_to_its_face():
    cube = part_from_mesh(shapes()["cube"][0])
    camera = Camera.look_at("front", (100.0, -100.0, 15.0), (100.0, 100.0, 15.0), focal_px=600.0)
    depth = render.render_depth(cube, camera, distorted=False)
    h, w = depth.shape
    assert depth[h // 2, w // 2] == pytest.approx(185.0, abs=0.01)  # front face at y = 85
    silhouette = render_silhouette(cube, camera, distorted=False)
    assert np.array_equal(np.isfinite(depth), silhouette)
    assert np.all(depth[silhouette] == pytest.approx(185.0, abs=0.01))


def test_new_band_is_what_was_printed_since_the_previous_check():
    cube = part_from_mesh(shapes()["cube"][0])
    # Eye level with the previous top (z = 10): its top face is edge-on, the new top is seen from below.
    camera = Camera.look_at("level", (100.0, -100.0, 10.0), (100.0, 100.0, 10.0), focal_px=600.0,
                            dist=[-0.1, 0.0, 0.0, 0.0, 0.0])
    view = render_view(cube, camera, z=20.0, z_previous=10.0)
    earlier = render_silhouette(cube, camera, z=10.0)
    # So the newest band is exactly the silhouette added since z = 10.
    added = view.silhouette & ~earlier
    assert np.count_nonzero(view.new_band ^ added) < 0.02 * added.sum()
    assert not np.any(view.new_band & ~view.silhouette)
    rows = np.nonzero(view.new_band_undistorted.any(axis=1))[0]
    expected_rows = 600.0 * 10.0 / 185.0  # 10 mm at 185 mm, face-on
    assert len(rows) == pytest.approx(expected_rows, abs=2)


def test_gcode_silhouette_matches_the_stl_and_leaves_the_skirt_out(corpus, gcode_part):
    name = "prusa25_cylinder.gcode"
    part = gcode_part(name)
    placed = part_from_mesh(place_mesh_on_gcode(corpus / "cylinder.stl", corpus / name).mesh)
    camera = Camera.look_at("cam", (100.0, -60.0, 90.0), (100.0, 100.0, 10.0), focal_px=700.0)
    for z in (6.0, 30.0):
        got = render_silhouette(part, camera, z=z)
        want = render_silhouette(placed, camera, z=z)
        assert np.count_nonzero(got & want) / np.count_nonzero(got | want) > 0.97
    skirt = render_silhouette(part.apart, camera)
    stl_at_6 = cv2.dilate(render_silhouette(placed, camera, z=6.0).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    beside = skirt & ~stl_at_6
    assert beside.sum() > 100  # the skirt is visible beside the part ...
    assert not np.any(render_silhouette(part, camera, z=6.0) & beside)  # ... and never expected


def test_expected_views_are_cached_in_memory_and_on_disk(tmp_path, monkeypatch):
    part = part_from_mesh(shapes()["pyramid"][0])
    cameras = [oblique_camera(name="a"), oblique_camera(dist=[-0.2, 0.05, 0, 0, 0], name="b")]
    views = render_expected_views(part, cameras, [12.0, 6.0], cache_dir=tmp_path)
    assert sorted(views) == [("a", 6.0), ("a", 12.0), ("b", 6.0), ("b", 12.0)]
    assert views[("a", 12.0)].z_previous == 6.0 and views[("a", 6.0)].z_previous == 0.0
    assert len(list(tmp_path.glob("*.npz"))) == 4
    render._MEMORY_CACHE.clear()
    monkeypatch.setattr(render, "render_view", lambda *a, **k: pytest.fail("rendered again"))
    again = render_expected_views(part, cameras, [6.0, 12.0], cache_dir=tmp_path)
    for key, view in views.items():
        assert np.array_equal(again[key].silhouette, view.silhouette)
        assert np.array_equal(again[key].new_band, view.new_band)
        assert np.array_equal(again[key].depth, view.depth)
    monkeypatch.undo()
    render._MEMORY_CACHE.clear()
    damaged = sorted(tmp_path.glob("*.npz"))[0]
    damaged.write_bytes(b"not a cache file")
    redone = render_expected_views(part, cameras, [6.0, 12.0], cache_dir=tmp_path)
    assert all(np.array_equal(redone[k].silhouette, views[k].silhouette) for k in views)


def test_a_different_camera_does_not_reuse_the_cache(tmp_path):
    part = part_from_mesh(shapes()["cube"][0])
    first = render_expected_views(part, [oblique_camera(name="x")], [10.0], cache_dir=tmp_path)
    moved = oblique_camera(name="x").with_pose(oblique_camera().rvec, oblique_camera().tvec + [5.0, 0.0, 0.0])
    second = render_expected_views(part, [moved], [10.0], cache_dir=tmp_path)
    assert not np.array_equal(first[("x", 10.0)].silhouette, second[("x", 10.0)].silhouette)
    assert len(list(tmp_path.glob("*.npz"))) == 2


def test_part_leaving_the_field_of_view_does_not_fold_back_into_the_image():
    """A tall part running out of a strongly distorted view (the seed's tall-part limit): far outside
    the view the distortion polynomial turns back, which must not draw the part where it is not."""
    tower = trimesh.creation.box((20, 20, 400))
    tower.apply_translation((100.0, 100.0, 200.0))
    camera = Camera.look_at("low", (100.0, -60.0, 20.0), (100.0, 100.0, 20.0), focal_px=600.0,
                            dist=[-0.3, 0.0, 0.0, 0.0, 0.0])
    mask = render_silhouette(tower, camera, distorted=True)
    # Each mask pixel must see the tower: its ray (through the lens model) meets the ideal silhouette.
    ideal = render_silhouette(tower, camera, distorted=False)
    ys, xs = np.nonzero(mask)
    und = np.round(camera.undistort_points(np.column_stack([xs, ys]))).astype(int)
    inside = (und[:, 0] >= 0) & (und[:, 0] < camera.width) & (und[:, 1] >= 0) & (und[:, 1] < camera.height)
    assert np.mean(ideal[und[inside, 1], und[inside, 0]]) > 0.98
    assert mask[0].any() and mask[camera.height // 2].any()  # the tower runs up out of the image
    assert not mask[-1].any()  # and its top does not reappear at the bottom


def test_geometry_behind_the_camera_is_cut_at_the_camera():
    bar = trimesh.creation.box((20, 300, 10))  # runs beside the camera, half of it behind
    bar.apply_translation((120.0, 50.0, 5.0))
    camera = Camera.look_at("inside", (100.0, 40.0, 5.0), (100.0, 100.0, 5.0), focal_px=300.0)
    mask = render_silhouette(bar, camera, distorted=False)
    assert mask[:, camera.width // 2 + 40:].mean() > 0.2  # the bar fills the right of the view
    assert not mask[:, : camera.width // 2].any()  # and nothing appears on the left
    for row in mask[mask.any(axis=1)]:  # no streaks: each row one run
        assert np.count_nonzero(np.diff(row.astype(np.int8))) <= 2


def test_sequential_print_views_follow_the_print_order(gcode_part):
    """Two cubes printed one after the other: at layer 175 the first is finished, the second 5 mm tall."""
    from octoprint_printwatch.core.render import render_expected_views_by_layer

    part = gcode_part("prusa25_two_cubes_sequential.gcode")
    assert part.sequential
    first_done = part.solid_through_layer(150)
    assert first_done.extents == pytest.approx([30.0, 30.0, 30.0], abs=0.1)  # only the first cube
    camera = Camera.look_at("front", (300.0, 100.0, 60.0), (100.0, 100.0, 15.0), focal_px=500.0)  # both cubes in view
    views = render_expected_views_by_layer(part, [camera], [(175, 5.0), (150, 30.0)])
    assert sorted(views) == [("front", 150), ("front", 175)]
    at_175 = views[("front", 175)]
    assert np.array_equal(at_175.silhouette, render_silhouette(part.solid_through_layer(175), camera))
    assert at_175.silhouette.sum() > views[("front", 150)].silhouette.sum()
    # The newest band is the second cube's first 5 mm only: its pixels lie where the first cube is not.
    only_first = render_silhouette(first_done, camera)
    band = at_175.new_band
    assert band.sum() > 500 and np.count_nonzero(band & only_first) < 0.05 * band.sum()
    # By height alone, the finished part cut at 5 mm would show both cubes 5 mm tall: not the print's state.
    assert not np.array_equal(render_silhouette(part, camera, z=5.0), at_175.silhouette)
