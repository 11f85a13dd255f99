"""Occupancy-grid ``map`` obstacles: Nav2 map_io's semantics case by case, an independent
oracle (Pillow reads the image, shapely builds the blocked region cell by cell), Hypothesis
on random small maps, the bad files, and ``gfuzzy map`` end to end."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from gfuzzy.cli.main import main
from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.errors import SceneError
from gfuzzy.scene.scene import MapObstacle, load_scene

ROOT = Path(__file__).resolve().parent.parent
MAPS = ROOT / "scenes" / "maps"


# --------------------------------------------------------------------------- helpers


def write_map(folder: Path, pixels, *, name="m", fmt="png", mode=None, negate=0, occ=0.65, free=0.196,
              resolution=0.5, origin=(0.0, 0.0, 0.0), image_name=None, extra=""):  # fmt: skip
    """Write ``pixels`` (H, W) gray or (H, W, C) uint8 as an image and its map YAML."""
    folder.mkdir(parents=True, exist_ok=True)
    arr = np.asarray(pixels, dtype=np.uint8)
    image_name = image_name or f"{name}.{fmt}"
    Image.fromarray(arr).save(folder / image_name)
    lines = [
        f"image: {image_name}",
        f"resolution: {resolution!r}",
        f"origin: [{origin[0]!r}, {origin[1]!r}, {origin[2]!r}]",
        f"negate: {negate}",
        f"occupied_thresh: {occ!r}",
        f"free_thresh: {free!r}",
    ]
    if mode is not None:
        lines.append(f"mode: {mode}")
    (folder / f"{name}.yaml").write_text("\n".join(lines) + "\n" + extra)
    return folder / f"{name}.yaml"


def scene_text(map_file="m.yaml", unknown=None, bounds=None, robot="disc: 0.1", queries=""):
    spec = f"{{file: {map_file}" + (f", unknown: {unknown}" if unknown else "") + "}"
    out = ["version: 1", "name: t", f"robot: {{{robot}, vmax: 1.0}}", f"obstacles:\n  - map: {spec}"]
    if bounds is not None:
        out.insert(2, f"bounds: {list(bounds)}")
    return "\n".join(out) + "\n" + queries


def grid_of(tmp_path, pixels, unknown=None, **kw) -> MapObstacle:
    write_map(tmp_path, pixels, **kw)
    (tmp_path / "s.yaml").write_text(scene_text(unknown=unknown))
    scene = load_scene(tmp_path / "s.yaml")
    (grid,) = scene.obstacles
    return grid


# --------------------------------------------------------------------------- the oracle


def oracle_values(image_path: Path, mode="trinary", negate=0, occ=0.65, free=0.196) -> list[list[int]]:
    """Nav2's loadMapFromFile, pixel by pixel in plain Python (Pillow's getpixel)."""
    img = Image.open(image_path)
    alpha = img.mode in ("RGBA", "LA")
    rgba = img.convert("RGBA")
    w, h = img.size
    out = []
    for y in range(h):
        row = []
        for x in range(w):
            r, g, b, a = rgba.getpixel((x, y))
            ch = [r * 257, g * 257, b * 257]
            if mode == "trinary" and alpha:
                ch.append(a * 257)
            shade = sum(ch) / len(ch) / 65535.0
            o = shade if negate else 1.0 - shade
            if mode == "raw":
                p = int(shade * 255 + 0.5)
                row.append(p if 0 <= p <= 100 else -1)
            elif mode == "scale" and a != 255:
                row.append(-1)
            elif occ < o:
                row.append(100)
            elif o < free:
                row.append(0)
            elif mode == "scale":
                row.append(int(np.rint((o - free) / (occ - free) * 100.0)))
            else:
                row.append(-1)
        out.append(row)
    return out


def oracle_region(values, unknown_free, resolution, origin):
    """The blocked region, one shapely box per blocked cell, unioned."""
    h = len(values)
    boxes = []
    for i, row in enumerate(values):
        for j, val in enumerate(row):
            if val == 100 or (val == -1 and not unknown_free):
                x0 = origin[0] + j * resolution
                y0 = origin[1] + (h - 1 - i) * resolution
                boxes.append(shapely.box(x0, y0, x0 + resolution, y0 + resolution))
    return shapely.union_all(boxes) if boxes else shapely.Polygon()


def rects_region(grid: MapObstacle):
    r = grid.rects
    return shapely.union_all(shapely.box(r[:, 0], r[:, 1], r[:, 2], r[:, 3])) if len(r) else shapely.Polygon()


# --------------------------------------------------------------------------- Nav2 semantics


def test_trinary_default_values(tmp_path):
    # 0 black occupied, 254 free, 205 unknown with free_thresh 0.196 (1 - 205/255 = 0.19608)
    grid = grid_of(tmp_path, [[0, 254, 205]])
    assert grid.values.tolist() == [[100, 0, -1]]
    assert grid.blocked.tolist() == [[True, False, True]]
    grid = grid_of(tmp_path, [[0, 254, 205]], free=0.25)  # the depot's threshold: 205 is free
    assert grid.values.tolist() == [[100, 0, 0]]


def test_thresholds_are_strict_as_in_nav2(tmp_path):
    # negate: occ = shade; 51 -> 51*257/65535 = 0.2 exactly the double 0.2
    grid = grid_of(tmp_path, [[50, 51, 52]], negate=1, occ=0.2, free=0.1)
    assert grid.values.tolist() == [[-1, -1, 100]]  # 0.2 < 0.2 is false: not occupied
    grid = grid_of(tmp_path, [[50, 51, 52]], negate=1, occ=0.9, free=0.2)
    assert grid.values.tolist() == [[0, -1, -1]]  # 0.2 < 0.2 is false: not free


def test_negate_flips(tmp_path):
    grid = grid_of(tmp_path, [[0, 254, 255]], negate=1)
    assert grid.values.tolist() == [[0, 100, 100]]


def test_rgb_is_averaged(tmp_path):
    px = np.array([[[255, 0, 0], [255, 255, 0], [0, 0, 0], [254, 254, 254]]], dtype=np.uint8)
    grid = grid_of(tmp_path, px)
    # shades 1/3 (occ 0.667 > 0.65), 2/3 (occ 0.333: unknown), 0, 254/255
    assert grid.values.tolist() == [[100, -1, 100, 0]]


def test_alpha_in_trinary_is_averaged_in(tmp_path):
    # Nav2 appends alpha to the channels in trinary mode: (255, 255, 255, 0) -> shade 0.75
    px = np.array([[[255, 255, 255, 0], [0, 0, 0, 0], [254, 254, 254, 255], [255, 255, 255, 128]]], dtype=np.uint8)
    grid = grid_of(tmp_path, px)
    # occ 0.25 unknown; occ 1 occupied; free; shade (765+128)/1020 = 0.8755, occ 0.1245 free
    assert grid.values.tolist() == [[-1, 100, 0, 0]]


def test_gray_alpha_image(tmp_path):
    px = np.array([[[254, 255], [254, 0]]], dtype=np.uint8)  # LA: gray counts three times
    grid = grid_of(tmp_path, px)
    assert grid.values.tolist() == [[0, -1]]  # (3*254 + 0)/4/255 = 0.747: occ 0.253


def test_scale_mode(tmp_path):
    px = np.array([[[0, 0, 0, 255], [254, 254, 254, 255], [128, 128, 128, 255], [254, 254, 254, 254]]], dtype=np.uint8)
    grid = grid_of(tmp_path, px, mode="scale", occ=0.65, free=0.25)
    occ = 1 - 128 / 255
    cost = int(np.rint((occ - 0.25) / 0.4 * 100))
    assert grid.values.tolist() == [[100, 0, cost, -1]]  # alpha < 255: unknown
    assert grid.blocked.tolist() == [[True, False, False, True]]  # a cost does not block


def test_scale_cost_at_occupied_thresh_is_100(tmp_path):
    # occ == occupied_thresh exactly is not occupied, but its cost rints to 100 = lethal
    grid = grid_of(tmp_path, [[51]], mode="scale", negate=1, occ=0.2, free=0.1)
    assert grid.values.tolist() == [[100]]
    assert grid.blocked.tolist() == [[True]]


def test_raw_mode(tmp_path):
    grid = grid_of(tmp_path, [[0, 37, 100, 101, 255]], mode="raw", negate=1)  # negate plays no part
    assert grid.values.tolist() == [[0, 37, 100, -1, -1]]
    assert grid.blocked.tolist() == [[False, False, True, True, True]]
    grid = grid_of(tmp_path, [[0, 37, 100, 101, 255]], mode="raw", unknown="free")
    assert grid.blocked.tolist() == [[False, False, True, False, False]]


def test_unknown_free_or_blocked(tmp_path):
    assert grid_of(tmp_path, [[205, 0]]).blocked.tolist() == [[True, True]]
    assert grid_of(tmp_path, [[205, 0]], unknown="free").blocked.tolist() == [[False, True]]
    assert grid_of(tmp_path, [[205, 0]], unknown="blocked").blocked.tolist() == [[True, True]]


def test_row_zero_is_the_top_and_origin_the_lower_left(tmp_path):
    px = np.full((2, 3), 254, dtype=np.uint8)
    px[0, 2] = 0
    grid = grid_of(tmp_path, px, resolution=0.25, origin=(1.0, -2.0, 0.0))
    assert grid.rects.tolist() == [[1.5, -1.75, 1.75, -1.5]]
    assert grid.extent == (1.0, -2.0, 1.75, -1.5)


def test_bounds_default_to_the_maps_extent(tmp_path):
    write_map(tmp_path, np.full((4, 6), 254, np.uint8), resolution=0.5, origin=(-1.0, 2.0, 0.0))
    (tmp_path / "s.yaml").write_text(scene_text())
    assert load_scene(tmp_path / "s.yaml").bounds == (-1.0, 2.0, 2.0, 4.0)
    (tmp_path / "s.yaml").write_text(scene_text(bounds=[0, 0, 1, 3]))
    assert load_scene(tmp_path / "s.yaml").bounds == (0.0, 0.0, 1.0, 3.0)
    (tmp_path / "n.yaml").write_text("version: 1\nname: n\nrobot: {disc: 0.1, vmax: 1}\n")
    with pytest.raises(SceneError, match="bounds"):
        load_scene(tmp_path / "n.yaml")


def test_bounds_beyond_the_maps_warn_that_the_space_outside_is_free(tmp_path, caplog):
    # two maps side by side, (-1..2) x (2..4) and (2..5) x (2..4): bounds inside their union
    # are quiet, bounds reaching past it name where, once
    write_map(tmp_path, np.full((4, 6), 254, np.uint8), resolution=0.5, origin=(-1.0, 2.0, 0.0))
    write_map(tmp_path, np.full((4, 6), 254, np.uint8), name="b", resolution=0.5, origin=(2.0, 2.0, 0.0))
    two = "  - map: {file: b.yaml}\n"
    caplog.set_level("WARNING", logger="gfuzzy.scene")
    (tmp_path / "s.yaml").write_text(scene_text(bounds=[-1, 2, 5, 4]) + two)
    load_scene(tmp_path / "s.yaml")
    assert not caplog.records
    (tmp_path / "s.yaml").write_text(scene_text(bounds=[0, 2.5, 4, 3.5]))  # map m alone: x 2..4 outside
    load_scene(tmp_path / "s.yaml")
    (msg,) = [r.getMessage() for r in caplog.records]
    assert "s.yaml: bounds reach 2 m² beyond the map's image (within [2, 4] x [2.5, 3.5])" in msg
    caplog.clear()
    (tmp_path / "s.yaml").write_text(scene_text(bounds=[0, 2.5, 4, 3.5]) + two)
    load_scene(tmp_path / "s.yaml")
    assert not caplog.records


def test_plain_pgm_p2(tmp_path):
    (tmp_path / "p.pgm").write_text("P2\n3 1\n255\n0 254 205\n")
    write_map(tmp_path, [[0]], image_name="unused.png")
    (tmp_path / "m.yaml").write_text((tmp_path / "m.yaml").read_text().replace("unused.png", "p.pgm"))
    (tmp_path / "s.yaml").write_text(scene_text())
    (grid,) = load_scene(tmp_path / "s.yaml").obstacles
    assert grid.values.tolist() == [[100, 0, -1]]


# --------------------------------------------------------------------------- oracle


@pytest.mark.parametrize("name", ["depot", "small_house", "tb3_sandbox"])
def test_real_maps_against_the_oracle(name):
    import yaml

    meta = yaml.safe_load((MAPS / f"{name}.yaml").read_text())
    scene = load_scene_text(scene_text(f"maps/{name}.yaml"), ROOT / "scenes")
    (grid,) = scene.obstacles
    want = oracle_values(MAPS / meta["image"], meta.get("mode", "trinary"), meta["negate"],
                         meta["occupied_thresh"], meta["free_thresh"])  # fmt: skip
    assert grid.values.tolist() == want
    # the rectangles cover the blocked cells exactly, without overlap
    r = grid.rects
    area = np.sum((r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1]))
    assert area == pytest.approx(grid.blocked.sum() * grid.resolution**2, rel=1e-9)
    assert rects_region(grid).area == pytest.approx(area, rel=1e-9)


def load_scene_text(text: str, folder: Path):
    from gfuzzy.scene.scene import parse_scene
    from gfuzzy.scene.yamldoc import _load_yaml

    return parse_scene(_load_yaml(text, "s.yaml"), file="s.yaml", folder=folder)


BUMPER = ((0.3, 0.0), (0.1, 0.2), (-0.2, 0.2), (-0.2, -0.2), (0.1, -0.2))
# concave, its reference point (the origin) in the notch, outside the body
NOTCHED = ((0.4, 0.3), (-0.3, 0.3), (-0.3, -0.3), (0.4, -0.3), (0.4, -0.1), (-0.1, -0.1), (-0.1, 0.1), (0.4, 0.1))

small_maps = st.integers(1, 9).flatmap(
    lambda h: st.integers(1, 9).flatmap(
        lambda w: st.lists(
            st.lists(st.sampled_from([0, 30, 100, 180, 205, 230, 254, 255]), min_size=w, max_size=w),
            min_size=h, max_size=h,
        )
    )
)  # fmt: skip


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    pixels=small_maps,
    resolution=st.sampled_from([0.05, 0.1, 0.3, 1.0]),
    ox=st.floats(-5, 5, allow_nan=False),
    oy=st.floats(-5, 5, allow_nan=False),
    mode=st.sampled_from(["trinary", "scale", "raw"]),
    negate=st.sampled_from([0, 1]),
    unknown=st.sampled_from(["blocked", "free"]),
    robot=st.sampled_from([("disc", 0.01), ("disc", 0.2), ("disc", 0.7), ("box", (0.5, 0.2)), ("box", (1.5, 0.4)),
                           ("footprint", BUMPER), ("footprint", NOTCHED)]),  # fmt: skip
    keep=st.sampled_from([0.0, 0.0, 0.05, 0.3]),
    data=st.data(),
)
def test_random_maps_fcl_and_oracle_agree(tmp_path, pixels, resolution, ox, oy, mode, negate, unknown, robot, keep, data):
    folder = tmp_path / f"r{abs(hash((str(pixels), ox, oy, mode))) % 10**9}"
    write_map(folder, pixels, mode=mode, negate=negate, occ=0.6, free=0.3, resolution=resolution, origin=(ox, oy, 0.0))
    h, w = len(pixels), len(pixels[0])
    bounds = [ox - 1, oy - 1, ox + w * resolution + 1, oy + h * resolution + 1]
    shape, size = robot
    if shape == "footprint":
        local = np.array(size)
        radius = float(np.max(np.hypot(local[:, 0], local[:, 1])))
        spec = "footprint: " + str([list(p) for p in size])
    elif shape == "box":
        hl, hw = size[0] / 2, size[1] / 2
        local = np.array([(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw)])
        radius = float(np.hypot(*size)) / 2
        spec = f"box: [{size[0]}, {size[1]}]"
    else:
        radius, spec = size, f"disc: {size}"
    bounds = [bounds[0] - radius, bounds[1] - radius, bounds[2] + radius, bounds[3] + radius]
    spec += f", clearance: {keep}"
    (folder / "s.yaml").write_text(scene_text(unknown=unknown, bounds=bounds, robot=spec))
    scene = load_scene(folder / "s.yaml")
    (grid,) = scene.obstacles
    values = oracle_values(folder / "m.png", mode, negate, 0.6, 0.3)
    assert grid.values.tolist() == values
    region = oracle_region(values, unknown == "free", resolution, (ox, oy))
    assert rects_region(grid).symmetric_difference(region).area == pytest.approx(0.0, abs=1e-9)
    geo = StaticGeometry(scene)
    unit = st.floats(0, 1)
    pts = np.array(data.draw(st.lists(st.tuples(unit, unit, unit), min_size=20, max_size=20)))
    lo = np.array([bounds[0], bounds[1]]) + radius + 0.01  # the body inside the bounds
    pts[:, :2] = lo + pts[:, :2] * np.array([bounds[2] - bounds[0], bounds[3] - bounds[1]]) - 2 * (radius + 0.01) * pts[:, :2]
    pts[:, 2] = (pts[:, 2] - 0.5) * 2 * np.pi
    for p in pts:
        tol = 1e-6 if keep == 0 else 2e-4  # FCL distances carry a 1e-4 safety margin
        if shape == "disc":
            d = region.distance(shapely.Point(p[:2])) if not region.is_empty else np.inf
            if abs(d - radius - keep) < tol:
                continue  # touching: either answer is right
            assert geo.is_valid(p[:2]) == (d > radius + keep), (p, d)
        else:
            c, s_ = np.cos(p[2]), np.sin(p[2])
            body = shapely.Polygon([(p[0] + c * a - s_ * b, p[1] + s_ * a + c * b) for a, b in local])
            overlap = body.intersection(region).area if not region.is_empty else 0.0
            gap = body.distance(region) if not region.is_empty else np.inf
            if overlap < 1e-9 and abs(gap - keep) < tol:
                continue  # touching
            assert geo.is_valid(p) == (overlap < 1e-9 and gap > keep), (p, overlap, gap)


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10_000), res=st.sampled_from([0.1, 0.2]))
def test_plans_on_random_maps_pass_check(tmp_path, seed, res):
    rng = np.random.default_rng(seed)
    px = np.where(rng.random((30, 30)) < 0.12, 0, 254).astype(np.uint8)
    px[rng.random((30, 30)) < 0.05] = 205
    px[:, :3] = 254  # a free column at each side for the start and the goal
    px[:, -3:] = 254
    px[14:16, :] = 254  # and a free row between them
    folder = tmp_path / f"p{seed}-{res}"
    write_map(folder, px, resolution=res, origin=(0.0, 0.0, 0.0))
    side = 30 * res
    query = f"queries:\n  - {{name: q, start: [{res}, {side / 2}], goal: [{side - res}, {side / 2}]}}\n"
    (folder / "s.yaml").write_text(scene_text(robot=f"disc: {res * 0.4}", queries=query))
    out = folder / "out.json"
    code = main(["plan", str(folder / "s.yaml"), "-n", "200", "--seed", "3", "-o", str(out)])
    assert code == 0  # the free row connects them
    assert main(["check", str(folder / "s.yaml"), str(out)]) == 0


# --------------------------------------------------------------------------- bad files


def _bad(tmp_path, capsys, expect: str):
    out = tmp_path / "out.json"
    code = main(["plan", str(tmp_path / "s.yaml"), "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and expect in err, err
    assert not out.exists()
    return err


def _good(tmp_path, **kw):
    write_map(tmp_path, [[254, 254], [254, 0]], **kw)
    (tmp_path / "s.yaml").write_text(scene_text(queries="queries:\n  - {name: q, start: [0.2, 0.8], goal: [0.8, 0.8]}\n"))


@pytest.mark.parametrize(
    "edit, expect",
    [
        (lambda d: (d / "m.yaml").unlink(), "obstacles[0].map.file: cannot read map 'm.yaml': no such file"),
        (lambda d: ((d / "m.yaml").unlink(), (d / "m.yaml").mkdir()), "map.file: cannot read map 'm.yaml': a folder, not a file"),
        (lambda d: (d / "m.png").unlink(), "m.png"),
        (lambda d: (d / "m.png").write_bytes((d / "m.png").read_bytes()[:40]), "m.png"),
        (lambda d: (d / "m.png").write_text("not an image"), "not an image"),
        (lambda d: _set(d, "resolution: 0.5", "resolution: 0"), "resolution"),
        (lambda d: _set(d, "resolution: 0.5", "resolution: fine"), "resolution"),
        (lambda d: _set(d, "origin: [0.0, 0.0, 0.0]", "origin: [0.0, 0.0, 0.3]"), "origin[2]"),
        (lambda d: _set(d, "origin: [0.0, 0.0, 0.0]", "origin: [0.0, 0.0]"), "origin"),
        (lambda d: _set(d, "negate: 0", "negate: 2"), "negate"),
        (lambda d: _set(d, "free_thresh: 0.196", "free_thresh: 0.7"), "free_thresh"),
        (lambda d: _set(d, "occupied_thresh: 0.65", "occupied_thresh: 1.5"), "free_thresh"),
        (lambda d: _set(d, "free_thresh: 0.196", ""), "free_thresh"),
        (lambda d: _set(d, "negate: 0", "negate: 0\nmode: fancy"), "mode"),
        (lambda d: _set(d, "image: m.png", "image: ../m.png"), "leaves"),
        (lambda d: _set(d, "image: m.png", "image: /etc/passwd"), "leaves"),
        (lambda d: _set(d, "image: m.png", "image: ~/m.png"), "relative"),
        (lambda d: (d / "m.yaml").write_text("image: [unclosed"), "m.yaml"),
        (lambda d: (d / "s.yaml").write_text(scene_text("../m.yaml")), "leaves"),
        (lambda d: (d / "s.yaml").write_text(scene_text(unknown="maybe")), "unknown"),
    ],
)
def test_bad_map_files_give_one_line(tmp_path, capsys, edit, expect):
    _good(tmp_path)
    edit(tmp_path)
    _bad(tmp_path, capsys, expect)


@pytest.mark.parametrize("command", ["plan", "render"])
def test_a_resolution_below_the_floats_spacing_is_bad_input(tmp_path, capsys, command):
    # resolution 1e-300 at origin -10: the map's extent, the scene's bounds, had zero width
    # (-10 + 2 x 1e-300 == -10) and render raised ZeroDivisionError (found by s39-newuser)
    _good(tmp_path, resolution=1e-300, origin=(-10.0, -10.0, 0.0))
    out = tmp_path / ("out.json" if command == "plan" else "out.png")
    assert main([command, str(tmp_path / "s.yaml"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == (f"{tmp_path / 'm.yaml'}: resolution: 1e-300 m is too small: floats are 1.77636e-15 m apart at "
                   "the map's coordinates (origin (-10, -10)), so its cells would have no size\n")
    assert not out.exists()


def test_a_resolution_just_above_the_floats_spacing_loads(tmp_path):
    _good(tmp_path, resolution=1e-12, origin=(-10.0, -10.0, 0.0))
    scene = load_scene(tmp_path / "s.yaml")
    assert scene.bounds[0] < scene.bounds[2] and scene.bounds[1] < scene.bounds[3]


def test_an_absolute_image_path_inside_the_folder_is_read_as_nav2_reads_it(tmp_path, capsys):
    # map YAML files often name their image by an absolute path (Nav2 takes it as written):
    # it was refused ("must be relative") even when the image lay beside the scene
    _good(tmp_path)
    _set(tmp_path, "image: m.png", f"image: {(tmp_path / 'm.png').resolve()}")
    (grid,) = load_scene(tmp_path / "s.yaml").obstacles
    assert grid.blocked.tolist() == [[False, False], [False, True]]
    assert grid.info.image == (tmp_path / "m.png").resolve()
    (tmp_path / "a").mkdir()
    shutil.move(tmp_path / "s.yaml", tmp_path / "a" / "s.yaml")
    shutil.move(tmp_path / "m.yaml", tmp_path / "a" / "m.yaml")
    # the image is now outside the scene's folder: refused, naming the key and what to do
    code = main(["plan", str(tmp_path / "a" / "s.yaml"), "-o", str(tmp_path / "out.json")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"{tmp_path / 'a' / 'm.yaml'}: image: ") and "leaves the scene file's folder" in err


def test_a_huge_image_is_refused_in_one_line_without_pillows_warning(tmp_path, capsys):
    # a PNG header of 10000 x 10000 pixels (no pixel data needed): Pillow warned of a
    # "decompression bomb" on stderr (two more lines) before our own limit refused it
    import struct
    import warnings
    import zlib

    _good(tmp_path)
    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    head = chunk(b"IHDR", struct.pack(">IIBBBBB", 10000, 10000, 8, 0, 0, 0, 0))
    (tmp_path / "m.png").write_bytes(b"\x89PNG\r\n\x1a\n" + head + chunk(b"IDAT", zlib.compress(b"\0" * 64)))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _bad(tmp_path, capsys, "image of 10000 x 10000 pixels")
    assert not [w for w in caught if issubclass(w.category, Image.DecompressionBombWarning)]


def _unread_image(monkeypatch, name):
    """Make reading the image's bytes fail the test: the size is refused from the header."""
    from gfuzzy.scene import maps

    real = maps._read_bytes

    def read(v, path, place, what):
        assert Path(path).name != name, f"{name} was read whole before its size was checked"
        return real(v, path, place, what)

    monkeypatch.setattr(maps, "_read_bytes", read)


@pytest.mark.parametrize("comment", [b"", b"# made by hand\n"])
def test_a_pgm_too_big_is_refused_from_its_header_naming_the_limit(tmp_path, capsys, monkeypatch, comment):
    from gfuzzy.scene import maps

    _good(tmp_path, fmt="pgm")
    (tmp_path / "m.pgm").write_bytes(b"P5\n" + comment + b"40 30\n255\n" + bytes(40 * 30))
    monkeypatch.setattr(maps, "MAX_MAP_CELLS", 1000)  # 40 x 30 = 1200 cells
    _unread_image(monkeypatch, "m.pgm")
    _bad(tmp_path, capsys, "image of 40 x 30 pixels, more than gfuzzy's limit MAX_MAP_CELLS (1,000 cells)")


def test_a_sparse_60000_square_pgm_is_refused_at_once(tmp_path, capsys, monkeypatch):
    # the new user's map: a 3.6 GB file of zeros took 19 s and 3.6 GB of memory to refuse
    _good(tmp_path, fmt="pgm")
    header = b"P5\n60000 60000\n255\n"
    with open(tmp_path / "m.pgm", "wb") as fh:
        fh.write(header)
        fh.truncate(len(header) + 60000 * 60000)  # sparse: no disc, no time
    _unread_image(monkeypatch, "m.pgm")
    _bad(tmp_path, capsys, "image of 60000 x 60000 pixels, more than gfuzzy's limit MAX_MAP_CELLS")


def test_a_png_beyond_pillows_own_bound_is_refused_from_its_header(tmp_path, capsys, monkeypatch):
    import struct
    import zlib

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    _good(tmp_path)
    head = chunk(b"IHDR", struct.pack(">IIBBBBB", 60000, 60000, 8, 0, 0, 0, 0))
    (tmp_path / "m.png").write_bytes(b"\x89PNG\r\n\x1a\n" + head + chunk(b"IDAT", zlib.compress(b"\0" * 64)))
    _unread_image(monkeypatch, "m.png")
    _bad(tmp_path, capsys, "more than gfuzzy's limit MAX_MAP_CELLS")


def test_a_big_map_loads_without_full_size_float_copies(tmp_path):
    # the image became (H, W, 4) float64 quanta, twice over, and every value step a full-size
    # float array: 60 bytes a cell at the peak (a 4000 x 4000 SLAM map took 1 GB to load, and
    # the 64-million-cell limit was out of reach); integer quanta and blocks of rows: 13 on it
    import tracemalloc

    px = np.tile(np.asarray(Image.open(MAPS / "small_house.pgm")), (2, 2))  # 1000 x 1000
    write_map(tmp_path, px, resolution=0.05)
    spec = {"file": "m.yaml"}
    from gfuzzy.scene.maps import load_map

    tracemalloc.start()
    try:
        grid = load_map(spec, "obstacles[0].map", "s.yaml", tmp_path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak / px.size < 36, peak / px.size  # 25 here (a quarter-million-cell block of rows)
    assert np.array_equal(grid.values, np.where(px == 0, 100, np.where(px == 254, 0, -1)))


@pytest.mark.parametrize("mode", ["trinary", "scale", "raw"])
def test_values_computed_in_blocks_of_rows_match_the_oracle(tmp_path, monkeypatch, mode):
    from gfuzzy.scene import maps

    monkeypatch.setattr(maps, "_BLOCK_CELLS", 10)  # 2 rows of 5 cells a block, and a last short one
    rng = np.random.default_rng(2)
    px = rng.integers(0, 256, size=(9, 5, 4), dtype=np.uint8)
    px[..., 3] = np.where(rng.random((9, 5)) < 0.3, 128, 255)
    grid = grid_of(tmp_path, px, mode=mode)
    assert grid.values.tolist() == oracle_values(tmp_path / "m.png", mode=mode)


def _old_free_cell_draw(grid, bounds, rng):
    """The draw as it was first written: every free centre in the bounds, then one of them."""
    c = grid.free_centres()
    xmin, ymin, xmax, ymax = bounds
    c = c[(c[:, 0] > xmin) & (c[:, 0] < xmax) & (c[:, 1] > ymin) & (c[:, 1] < ymax)]
    return lambda: c[int(rng.integers(len(c)))] + (rng.random(2) - 0.5) * grid.resolution


def test_free_cell_draw_keeps_indices_not_centres(tmp_path):
    # it held every free cell's centre (and built it twice, with the row and column
    # indices): 216 MB at the peak on a 4000 x 4000 map, kept while the roadmap grows;
    # now one flat index per free cell, and the same points for the same seed
    import tracemalloc

    from gfuzzy.scene.maps import free_cell_draw

    px = np.tile(np.asarray(Image.open(MAPS / "small_house.pgm")), (2, 2))  # 1000 x 1000
    grid = grid_of(tmp_path, px, resolution=0.05, origin=(-3.0, 1.0, 0.0))
    bounds = (-1.0, 2.0, 40.0, 45.0)
    tracemalloc.start()
    try:
        draw = free_cell_draw([grid], bounds, np.random.default_rng(7), share=1.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak / px.size < 6, peak / px.size  # bytes per cell of the map: 13.5 before, 3.5 now
    old = _old_free_cell_draw(grid, bounds, np.random.default_rng(7))
    for _ in range(200):
        assert np.array_equal(draw(), old())


def test_the_good_map_of_the_bad_cases_loads(tmp_path):
    _good(tmp_path)
    (grid,) = load_scene(tmp_path / "s.yaml").obstacles
    assert grid.blocked.tolist() == [[False, False], [False, True]]


def _set(folder: Path, old: str, new: str) -> None:
    text = (folder / "m.yaml").read_text()
    assert old in text
    (folder / "m.yaml").write_text(text.replace(old, new))


# --------------------------------------------------------------------------- gfuzzy map


def test_gfuzzy_map_end_to_end(tmp_path, capsys):
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        shutil.copy(MAPS / f, tmp_path / "maps" / f) if (tmp_path / "maps").exists() else (
            (tmp_path / "maps").mkdir(), shutil.copy(MAPS / f, tmp_path / "maps" / f))  # fmt: skip
    out = tmp_path / "arena.yaml"
    assert main(["map", str(tmp_path / "maps" / "tb3_sandbox.yaml"), "--robot-disc", "0.2", "-o", str(out)]) == 0
    text = out.read_text()
    assert "file: maps/tb3_sandbox.yaml" in text and text.startswith("#")
    scene = load_scene(out)
    start, goal = np.array(scene.queries[0].start), np.array(scene.queries[0].goal)
    assert np.hypot(*(start - goal)) > 3.0  # far apart in a 5 m arena
    traj = tmp_path / "t.json"
    assert main(["plan", str(out), "-o", str(traj)]) == 0
    assert main(["check", str(out), str(traj)]) == 0


def test_gfuzzy_map_says_when_the_robot_fits_nowhere(tmp_path, capsys):
    # it said only "wrote ...", and `gfuzzy plan` then said "the scene has no queries"
    _good(tmp_path)
    out = tmp_path / "big.yaml"
    assert main(["map", str(tmp_path / "m.yaml"), "--robot-disc", "5", "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert f"wrote {out}" in captured.out
    assert captured.err.strip() == (
        f"note: the robot fits nowhere on this map (a disc of radius 5): {out} has no sample query (a smaller robot?)"
    )
    assert not load_scene(out).queries


@pytest.mark.parametrize("resolution, origin", [(5e8, (0.0, 0.0, 0.0)), (0.5, (-1e9, 999999999.0, 0.0))])
def test_gfuzzy_map_of_a_map_reaching_past_a_scenes_bound_names_the_map(tmp_path, capsys, resolution, origin):
    # it said "s.yaml: bounds[2]: number too large": a place in the output file it had not written
    m = write_map(tmp_path, np.full((4, 6), 254), resolution=resolution, origin=origin)
    out = tmp_path / "s.yaml"
    assert main(["map", str(m), "--robot-disc", "0.1", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"{m}: resolution: the map's far corner ("), err
    assert "lies beyond 1e+09 in magnitude" in err and not out.exists()


@pytest.mark.parametrize("stem", ["12", "null", "1e3"])
def test_gfuzzy_map_of_a_scene_named_like_a_number(tmp_path, capsys, stem):
    # `-o 12.yaml` wrote "name: 12", which reads as a number: refused as it was written
    _good(tmp_path)
    out = tmp_path / f"{stem}.yaml"
    assert main(["map", str(tmp_path / "m.yaml"), "--robot-disc", "0.1", "-o", str(out)]) == 0, capsys.readouterr().err
    assert load_scene(out).name == stem


@pytest.mark.parametrize(
    "stem", ["map,v2", "house #2", "a: b", "[x]", "{y}", "a]b", "p{q}", "x, y", "..m", "line\nbreak", "a\u2028b"]
)
def test_gfuzzy_map_of_a_map_file_named_with_yaml_signs(tmp_path, capsys, stem):
    # the map's path was written plain into `{file: ..., unknown: blocked}`: a comma, a ' #',
    # a ': ' or brackets broke the line and `gfuzzy map` refused its own scene (exit 2); a
    # line break in the name broke the comments that quote it; "..m.yaml" was "outside"
    write_map(tmp_path, [[254, 254], [254, 0]], name=stem, image_name="m.png")
    out = tmp_path / "s.yaml"
    code = main(["map", str(tmp_path / f"{stem}.yaml"), "--robot-disc", "0.1", "-o", str(out)])
    assert code == 0, capsys.readouterr().err
    (grid,) = load_scene(out).obstacles
    assert grid.file == f"{stem}.yaml"
    assert grid.blocked.tolist() == [[False, False], [False, True]]


@pytest.mark.parametrize("fmt", ["png", "pgm", "pgm-plain"])
def test_gfuzzy_map_given_the_image_says_so(tmp_path, capsys, fmt):
    # `gfuzzy map house.pgm` said only "not UTF-8 text (byte 52)" (a plain P2 PGM: "expected
    # a mapping, got a string")
    write_map(tmp_path, [[254, 254], [254, 0]], fmt="png" if fmt == "pgm-plain" else fmt)
    if fmt == "pgm-plain":
        (tmp_path / "m.pgm-plain").write_text("P2\n2 2\n255\n254 254\n254 0\n")
    assert main(["map", str(tmp_path / f"m.{fmt}"), "-o", str(tmp_path / "s.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(str(tmp_path / f"m.{fmt}")), err
    assert "an image? name the map's YAML file" in err
    assert not (tmp_path / "s.yaml").exists()


def test_gfuzzy_map_of_a_map_far_from_the_origin(tmp_path, capsys):
    # numbers were written with 6 significant digits: a map at UTM-like coordinates got
    # bounds and a query ten metres off (5678123.25 -> 5.67813e+06): invalid_query
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        shutil.copy(MAPS / f, tmp_path / f)
    (tmp_path / "tb3_sandbox.yaml").write_text(
        (tmp_path / "tb3_sandbox.yaml").read_text().replace("origin: [-10.000000, -10.000000, 0.000000]", "origin: [351234.5, 5678123.25, 0]")
    )
    out = tmp_path / "far.yaml"
    assert main(["map", str(tmp_path / "tb3_sandbox.yaml"), "--robot-disc", "0.2", "-o", str(out)]) == 0
    scene = load_scene(out)
    (grid,) = scene.obstacles
    assert grid.origin == (351234.5, 5678123.25)
    x0, y0, x1, y1 = scene.bounds
    assert 351234.5 <= x0 < x1 <= 351234.5 + 19.2 and 5678123.25 <= y0 < y1 <= 5678123.25 + 19.2
    traj = tmp_path / "t.json"
    assert main(["plan", str(out), "-o", str(traj)]) == 0, capsys.readouterr().err
    assert main(["check", str(out), str(traj)]) == 0


def test_gfuzzy_map_refuses_a_map_outside_the_folder(tmp_path, capsys):
    write_map(tmp_path / "a", [[254, 254], [254, 254]])
    (tmp_path / "b").mkdir()
    out = tmp_path / "b" / "s.yaml"
    assert main(["map", str(tmp_path / "a" / "m.yaml"), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "inside the scene file's folder" in err
    assert not out.exists()
    assert main(["map", str(tmp_path / "a" / "m.yaml"), "--robot-footprint", "0", "0", "1", "-o", str(tmp_path / "a" / "s.yaml")]) == 2
    assert not (tmp_path / "a" / "s.yaml").exists()


@pytest.mark.parametrize(
    "value, message",
    [
        ("1e10", "number too large (1e+10; at most 1e+09 in magnitude)"),  # was blamed on s.yaml: robot.footprint[1][0]
        ("1e300", "number too large (1e+300"),  # the same, after a RuntimeWarning of shapely's
        ("1e-300", "polygon is degenerate: too small (it spans 1e-300 m"),  # was "not a simple polygon of positive area"
    ],
)
def test_gfuzzy_map_checks_the_footprint_as_a_scene_does_naming_the_option(tmp_path, capsys, value, message):
    write_map(tmp_path, [[254, 254], [254, 254]])
    out = tmp_path / "s.yaml"
    argv = ["map", str(tmp_path / "m.yaml"), "--robot-footprint", "0", "0", value, "0", "0", value, "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"--robot-footprint: {message}"), err
    assert not out.exists()


def test_gfuzzy_map_given_a_scene_file_says_so(tmp_path, capsys):
    # a scene handed where the map belongs said only "image: missing required key" (s39-newuser)
    (tmp_path / "hall.yaml").write_text("version: 1\nname: hall\nbounds: [0, 0, 5, 5]\nrobot: {disc: 0.2}\n")
    out = tmp_path / "s.yaml"
    assert main(["map", str(tmp_path / "hall.yaml"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"{tmp_path / 'hall.yaml'}: image: missing required key")
    assert "this is a gfuzzy scene file, not a ROS/Nav2 map YAML" in err and not out.exists()


def test_gfuzzy_map_blames_a_bad_name_on_the_option(tmp_path, capsys):
    # it was the written scene's `name:` (s.yaml: name: ...), a key the user never wrote
    write_map(tmp_path, [[254, 254], [254, 254]])
    out = tmp_path / "s.yaml"
    assert main(["map", str(tmp_path / "m.yaml"), "--name", "a b", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "gfuzzy map: name must be letters, digits, _ . - (got 'a b')"
    assert not out.exists()


def test_gfuzzy_map_with_a_footprint_writes_the_contract_key(tmp_path):
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        shutil.copy(MAPS / f, tmp_path / f)
    out = tmp_path / "fp.yaml"
    argv = ["map", str(tmp_path / "tb3_sandbox.yaml"), "--robot-footprint", "0.15", "0.1", "-0.1", "0.1", "-0.1", "-0.1", "0.15", "-0.1"]
    assert main([*argv, "-o", str(out)]) == 0
    import yaml

    doc = yaml.safe_load(out.read_text())
    assert doc["robot"]["footprint"] == [[0.15, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.15, -0.1]]
    assert "disc" not in doc["robot"] and "box" not in doc["robot"]
    q = doc["queries"][0]
    assert len(q["start"]) == 3 and len(q["goal"]) == 3
    # the footprint fits at both ends
    geo = StaticGeometry(load_scene(out))
    for pose in (q["start"], q["goal"]):
        assert geo.is_valid(pose), pose


def test_gfuzzy_map_writes_no_negative_zero(tmp_path):
    # a footprint given with "-0" (as a script printing rounded coordinates writes it) was
    # copied into the scene as "-0"
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        shutil.copy(MAPS / f, tmp_path / f)
    out = tmp_path / "fp.yaml"
    fp = ["0.15", "0.1", "-0.1", "0.1", "-0.12", "-0", "-0.1", "-0.1", "0.15", "-0.1"]
    assert main(["map", str(tmp_path / "tb3_sandbox.yaml"), "--robot-footprint", *fp, "-o", str(out)]) == 0
    line = next(ln for ln in out.read_text().splitlines() if "footprint:" in ln)
    assert "[-0.12, 0]" in line and "-0]" not in line, line


CART = ["0.7", "0.25", "-0.1", "0.25", "-0.1", "-0.25", "0.7", "-0.25"]  # 0.8 x 0.5, off-centre


def test_gfuzzy_map_finds_room_for_an_off_centre_cart(tmp_path, capsys):
    # the fit was the circumscribed disc (radius 0.74 about the reference point, 1.5 m
    # across): "the robot fits nowhere" in the tb3 arena, where the 0.8 x 0.5 cart drives
    # between the posts and the wall; now its footprint at heading 0, which it can translate
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        shutil.copy(MAPS / f, tmp_path / f)
    out = tmp_path / "cart.yaml"
    assert main(["map", str(tmp_path / "tb3_sandbox.yaml"), "--robot-footprint", *CART, "-o", str(out)]) == 0
    assert "fits nowhere" not in capsys.readouterr().err
    scene = load_scene(out)
    (q,) = scene.queries
    geo = StaticGeometry(scene)
    assert q.start[2] == 0.0 and q.goal[2] == 0.0
    assert geo.is_valid(q.start) and geo.is_valid(q.goal)
    assert np.hypot(q.goal[0] - q.start[0], q.goal[1] - q.start[1]) > 1.0
    traj = tmp_path / "t.json"
    # -n 100: the cart crosses as on the default 200 vertices (both answers 3.43 s long), and
    # the roadmap of its footprint costs half as much
    assert main(["plan", str(out), "-n", "100", "-o", str(traj)]) == 0
    assert main(["check", str(out), str(traj)]) == 0


def test_box_fit_keeps_its_margin_and_refuses_a_footprint_bigger_than_the_map(tmp_path):
    # the footprint's box must fit with a margin (a tenth of its radius and a cell): a
    # corridor it fits only exactly offers no sample query; and a footprint typed in
    # millimetres padded the grid by its size (8 GB on the tb3 map) instead of fitting nowhere
    import tracemalloc

    from gfuzzy.scene.mapscene import _box_fits, _fits

    fp = np.array([[0.1, 0.25], [-0.1, 0.25], [-0.1, -0.25], [0.1, -0.25]])
    r = float(np.hypot(0.1, 0.25))
    for free_rows, fits_somewhere in ((6, False), (9, True)):
        px = np.full((6 + free_rows, 40), 254, np.uint8)
        px[:3], px[-3:] = 0, 0
        grid = grid_of(tmp_path, px, resolution=0.1)
        fits, _ = _fits(grid, (0.0, 0.0, 4.0, 0.1 * len(px)), fp, r, "holonomic")
        assert fits.any() == fits_somewhere, free_rows
    tracemalloc.start()
    try:
        fits = _box_fits(grid, (0.0, 0.0, 4.0, 1.5), (-100.0, -250.0, 700.0, 250.0), 74.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert fits.shape == px.shape and not fits.any()
    assert peak < 1_000_000, peak


@pytest.mark.parametrize("seed", range(6))
def test_box_fit_against_shapely(tmp_path, seed):
    # every cell said to fit keeps the grown box clear of every blocked cell and inside the
    # bounds; every cell whose box grown by one more cell is clear is said to fit
    from gfuzzy.scene.mapscene import _box_fits

    rng = np.random.default_rng(seed)
    px = np.where(rng.random((14, 17)) < 0.12, 0, 254).astype(np.uint8)
    grid = grid_of(tmp_path, px, resolution=0.5, origin=(-1.0, 2.0, 0.0))
    x0, x1 = sorted(rng.uniform(-1.5, 1.5, 2))
    y0, y1 = sorted(rng.uniform(-1.0, 1.0, 2))
    grow, res = 0.1, 0.5
    bounds = (-0.5, 2.5, 7.0, 8.5)
    fits = _box_fits(grid, bounds, (x0, y0, x1, y1), grow)
    cells = shapely.union_all([shapely.box(*r) for r in grid.rects])
    h, w = px.shape
    for i in range(h):
        for j in range(w):
            cx, cy = -1.0 + (j + 0.5) * res, 2.0 + (h - 1 - i + 0.5) * res

            def clear(g, cx=cx, cy=cy):
                box = shapely.box(cx + x0 - g, cy + y0 - g, cx + x1 + g, cy + y1 + g)
                return box.within(shapely.box(*bounds)) and box.intersection(cells).area == 0.0
            if fits[i, j]:
                assert clear(grow), (i, j)
            else:
                assert not clear(grow + res), (i, j)
    assert 0 < fits.sum() < fits.size


def test_gfuzzy_map_writes_a_differential_drive(tmp_path, capsys):
    # a newcomer with a differential drive had to edit the scene (kinematics, and a heading
    # in every pose of a disc robot) before the first plan
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        shutil.copy(MAPS / f, tmp_path / f)
    out = tmp_path / "tb3.yaml"
    argv = ["map", str(tmp_path / "tb3_sandbox.yaml"), "--robot-disc", "0.11", "--kinematics", "unicycle"]
    assert main([*argv, "-o", str(out)]) == 0
    scene = load_scene(out)
    assert scene.robot.kinematics == "unicycle"
    assert len(scene.queries[0].start) == 3 and len(scene.queries[0].goal) == 3
    traj = tmp_path / "t.json"
    assert main(["plan", str(out), "-o", str(traj)]) == 0
    assert main(["check", str(out), str(traj)]) == 0
    # the cart as a differential drive must turn in place: its circumscribed disc does not fit
    cart = tmp_path / "cart.yaml"
    argv = ["map", str(tmp_path / "tb3_sandbox.yaml"), "--robot-footprint", *CART, "--kinematics", "unicycle"]
    assert main([*argv, "-o", str(cart)]) == 0
    assert "(its circumscribed disc, radius 0.7433, to turn in place)" in capsys.readouterr().err


def test_gfuzzy_map_writes_a_differential_drive_that_reverses(tmp_path, capsys):
    # a user whose base backs up had to edit the scene by hand (map had no --reverse), and
    # after populate the robot is one flow-style line a block edit misses
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        shutil.copy(MAPS / f, tmp_path / f)
    out = tmp_path / "tb3.yaml"
    argv = ["map", str(tmp_path / "tb3_sandbox.yaml"), "--kinematics", "unicycle", "--reverse", "-o", str(out)]
    assert main(argv) == 0
    robot = load_scene(out).robot
    assert robot.kinematics == "unicycle" and robot.reverse
    assert not load_scene(_map_to(tmp_path, "fwd.yaml", "--kinematics", "unicycle")).robot.reverse
    capsys.readouterr()
    bad = tmp_path / "bad.yaml"
    assert main(["map", str(tmp_path / "tb3_sandbox.yaml"), "--reverse", "-o", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "--reverse needs --kinematics unicycle" in err and "Traceback" not in err
    assert not bad.exists()


@pytest.mark.parametrize("reverse", [[], ["--reverse"]])
def test_gfuzzy_map_writes_a_differential_drives_turning_rate(tmp_path, capsys, reverse):
    # a newcomer's base turns at 0.4 rad/s: map had no --wmax, the bound was edited in by hand
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        shutil.copy(MAPS / f, tmp_path / f)
    robot = load_scene(_map_to(tmp_path, "w.yaml", "--kinematics", "unicycle", "--wmax", "0.4", *reverse)).robot
    assert robot.kinematics == "unicycle" and robot.wmax == 0.4 and robot.reverse == bool(reverse)
    assert load_scene(_map_to(tmp_path, "d.yaml", "--kinematics", "unicycle")).robot.wmax is None  # the default
    capsys.readouterr()
    bad = tmp_path / "bad.yaml"
    for flags, expect in [(["--wmax", "0.4"], "gfuzzy map: --wmax needs --kinematics unicycle"),  # as --reverse
                          (["--kinematics", "unicycle", "--wmax", "0"], "gfuzzy map: --wmax must be a positive number"),
                          (["--kinematics", "unicycle", "--wmax", "1e300"], "gfuzzy map: --wmax must be at most 1e+09"),
                          (["--kinematics", "unicycle", "--wmax", "nan"], "gfuzzy map: --wmax must be a positive number"),
                          (["--vmax", "1e300"], "gfuzzy map: --vmax must be at most 1e+09")]:  # fmt: skip
        assert main(["map", str(tmp_path / "tb3_sandbox.yaml"), *flags, "-o", str(bad)]) == 2, flags
        err = capsys.readouterr().err
        assert err.startswith(expect) and err.count("\n") == 1 and "Traceback" not in err, err
        assert not bad.exists()


def _map_to(folder, name, *flags):
    """The scene ``gfuzzy map`` writes around the tb3 map in ``folder`` with ``flags``."""
    out = folder / name
    assert main(["map", str(folder / "tb3_sandbox.yaml"), *flags, "-o", str(out)]) == 0
    return out


def test_render_draws_the_grid_at_its_place(tmp_path):
    px = np.full((20, 40), 254, dtype=np.uint8)
    px[:, :20] = 205  # the west half unknown (gray), the east half free
    px[1:5, 30:34] = 0  # an occupied block in the north-east (row 0 is the top)
    write_map(tmp_path, px, resolution=0.5, origin=(0.0, 0.0, 0.0))
    (tmp_path / "s.yaml").write_text(scene_text())
    out = tmp_path / "r.png"
    assert main(["render", str(tmp_path / "s.yaml"), "--no-roadmap", "-o", str(out)]) == 0
    img = np.asarray(Image.open(out).convert("L"), dtype=float)
    dark = img < 128
    rows, cols = np.nonzero(dark & (np.arange(img.shape[1]) > img.shape[1] * 0.55)[None, :])
    assert len(rows)  # the occupied block, drawn east of the middle
    gray = (img > 150) & (img < 220)
    west, east = gray[:, : img.shape[1] // 2].sum(), gray[:, img.shape[1] // 2 :].sum()
    assert west > 10 * max(east, 1)  # unknown cells drawn gray, on the west side only
    grow = np.nonzero(gray[:, : img.shape[1] // 2].any(axis=1))[0]  # the map's rows on the picture
    assert rows.mean() < 0.5 * (grow.min() + grow.max())  # the block in the north half


def test_render_draws_a_map_in_single_precision(tmp_path):
    # the grid's picture was an (H, W, 4) float64 array: 32 bytes a cell, 512 MB of a
    # 4000 x 4000 map (render peaked at 1.6 GB); float32 draws the same pixels
    from matplotlib.figure import Figure

    from gfuzzy.render.draw import _draw_map

    px = np.full((20, 40), 254, dtype=np.uint8)
    px[:, :20] = 205
    grid = grid_of(tmp_path, px)
    ax = Figure().add_subplot()
    _draw_map(ax, grid, (0.0, 0.0, 20.0, 10.0))
    (image,) = ax.get_images()
    assert image.get_array().dtype == np.float32


def test_tracks_on_a_map_scene_rewrite_the_map_path(tmp_path):
    folder = tmp_path / "arena"
    shutil.copytree(MAPS, folder / "maps")
    shutil.copy(ROOT / "scenes" / "tb3-arena.yaml", folder / "tb3-arena.yaml")
    csv = tmp_path / "people.csv"
    csv.write_text("t,id,x,y\n0,1,-2.0,0.55\n4,1,2.0,0.55\n")
    out = tmp_path / "people.yaml"  # one folder up: the map is now arena/maps/...
    argv = ["tracks", str(csv), "--static", str(folder / "tb3-arena.yaml"), "--start", "-2.4", "0", "--goal", "2.0", "0.3"]
    assert main([*argv, "-o", str(out)]) == 0
    assert "file: arena/maps/tb3_sandbox.yaml" in out.read_text()
    assert load_scene(out).static_hash == load_scene(folder / "tb3-arena.yaml").static_hash


def test_a_map_beside_other_obstacles_and_beyond_its_extent(tmp_path):
    px = np.full((10, 10), 254, dtype=np.uint8)
    px[4:6, 4:6] = 0  # a 1 m block at [2, 3] x [2, 3]
    write_map(tmp_path, px, resolution=0.5, origin=(0.0, 0.0, 0.0))
    text = scene_text(bounds=[-3, -3, 8, 8], robot="disc: 0.2, clearance: 0.1")
    text = text.replace("obstacles:\n", "obstacles:\n  - box: {center: [6.5, 6.5], size: [1, 1]}\n")
    (tmp_path / "s.yaml").write_text(text)
    geo = StaticGeometry(load_scene(tmp_path / "s.yaml"))
    assert not geo.is_valid((2.5, 2.5))  # inside the map's block
    assert not geo.is_valid((3.25, 2.5))  # 0.25 from it: within radius + clearance
    assert geo.is_valid((3.35, 2.5))  # 0.35 from it
    assert not geo.is_valid((5.75, 6.5))  # 0.25 from the box, off the map
    assert geo.is_valid((-2.0, -2.0))  # off the map: free
    assert geo.obstacle_clearance((2.5, 0.5)) == pytest.approx(1.5 - 0.2, abs=2e-4)  # below y = 2
