"""The replay page in a real browser (headless Chromium through Playwright): it loads without a
console error; after a seek, the paired UAVs are on screen where the recorded positions fall
under the page's camera, as read back through its hook and as seen in screenshot pixels; the
controls (scrub, play, closest pass, pick and follow) do what they say; a replay of an env
episode recorded through RecordEpisode and the replays in the docs load and play.

Skips, naming the Debian package ``chromium``, where the browser is absent (fails instead
when ``PAIRFLOCK_REQUIRE_BROWSER=1``, as CI sets it)."""

from __future__ import annotations

import os
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

import pairflock_env as pf
from pairflock_env.envs.record import RecordEpisode
from pairflock_env.recording import open_recording
from pairflock_env.replay import build_replay, headless, write_demo

_WHY = headless.missing()
if _WHY and os.environ.get("PAIRFLOCK_REQUIRE_BROWSER") == "1":
    raise RuntimeError(f"PAIRFLOCK_REQUIRE_BROWSER=1, but: {_WHY}")
pytestmark = pytest.mark.skipif(_WHY is not None, reason=f"replay browser tests: {_WHY}")

SIZE = (960, 600)
STEP = 30  # t = 1.5 s: away from the closest pass (its rings would cover UAVs)
BACKGROUND = np.array([16, 20, 26])
#: the replays the docs embed (docs/replays/make_replays.py writes them)
DOCS_REPLAYS = sorted((Path(__file__).resolve().parents[2] / "docs" / "replays").glob("*.html"))


def png_pixels(data: bytes) -> np.ndarray:
    """The (H, W, 3) pixels of an 8-bit RGB or RGBA, non-interlaced PNG (small ones)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos : pos + 8])
        body = data[pos + 8 : pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and color in (2, 6) and interlace == 0
            ch = 3 if color == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, out, stride = zlib.decompress(idat), [], w * ch
    prev = [0] * stride
    for y in range(h):
        f, row = raw[y * (stride + 1)], list(raw[y * (stride + 1) + 1 : (y + 1) * (stride + 1)])
        for x in range(stride):
            a = row[x - ch] if x >= ch else 0
            b, c = prev[x], prev[x - ch] if x >= ch else 0
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            paeth = a if pa <= pb and pa <= pc else b if pb <= pc else c
            row[x] = (row[x] + (0, a, b, (a + b) // 2, paeth)[f]) & 255
        out.append(row)
        prev = row
    return np.array(out, np.uint8).reshape(h, w, ch)[..., :3]


@pytest.fixture(scope="module")
def browser():
    with headless.launch() as b:
        yield b


@pytest.fixture(scope="module", params=[3, 2], ids=["3d", "2d"])
def replay(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp(f"replay{request.param}")
    rec = write_demo(folder / "demo.pfrec", num_uavs=10, steps=120, dim=request.param)
    build_replay(rec, folder / "demo.html")
    return open_recording(rec), folder / "demo.html"


@pytest.fixture
def page(browser, replay):
    page, errors = headless.open_replay(browser, replay[1], SIZE)
    yield page
    assert errors == [], f"console errors: {errors}"
    page.close()


def _hook(page, expr: str):
    return page.evaluate(f"window.pairflockReplay.{expr}")


def _next_frame(page) -> None:
    page.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")


def _project(page, points: np.ndarray) -> np.ndarray:
    """CSS pixel positions (x right, y down) and NDC depth of world points under the page's
    camera, computed here from its view-projection matrix."""
    m = np.array(_hook(page, "viewProjection()")).reshape(4, 4).T  # column-major
    size = _hook(page, "canvasSize()")
    p = np.c_[points, np.ones(len(points))] @ m.T
    ndc = p[:, :3] / p[:, 3:]
    x = (ndc[:, 0] + 1) / 2 * size["cssWidth"]
    y = (1 - ndc[:, 1]) / 2 * size["cssHeight"]
    return np.c_[x, y, ndc[:, 2]]


def _pixel(page, x: float, y: float) -> np.ndarray:
    clip = {"x": int(x) - 1, "y": int(y) - 1, "width": 3, "height": 3}
    return png_pixels(page.screenshot(clip=clip))[1, 1].astype(int)


def check_screen_positions(page, rec, step: int, least: int) -> None:
    """After seeking to ``step``: each paired UAV is drawn where the recorded position falls
    under the page's camera (the hook's projection and the screenshot's pixel colour)."""
    page.add_style_tag(content=".box { display: none !important; }")  # panels off the pixels
    assert _hook(page, f"seek({step})") == step and _hook(page, "step") == step
    _next_frame(page)
    q = np.zeros((rec.num_uavs, 3))
    q[:, : rec.dim] = np.asarray(rec["positions"][step], np.float64)
    q[:, : rec.dim] -= _hook(page, "offset")[: rec.dim]
    screen = _project(page, q)
    size = _hook(page, "canvasSize()")
    radius = np.array([_hook(page, f"uavPixelSize({i})") for i in range(rec.num_uavs)]) / 2
    decoded = np.array([_hook(page, f"uavPosition({i})") for i in range(rec.num_uavs)])
    np.testing.assert_allclose(decoded, rec["positions"][step], atol=2e-3)  # quantised, < 1 mm
    checked = 0
    for i in rec.pairs.ravel():
        x, y, z = screen[i]
        hook_xy = _hook(page, f"projectUav({i})")
        assert np.hypot(hook_xy[0] - x, hook_xy[1] - y) < 0.5, (i, hook_xy, (x, y))
        assert 0 < x < size["cssWidth"] and 0 < y < size["cssHeight"] and -1 < z < 1
        covered = [
            j
            for j in range(rec.num_uavs)
            if j != i and np.hypot(*(screen[j, :2] - screen[i, :2])) < radius[j] + 1
        ]
        if covered:  # another UAV's disc overlaps this centre: its colour may win
            continue
        want = np.array(_hook(page, f"uavColor({i})"))
        got = _pixel(page, x, y)
        assert np.abs(got - want).max() <= 20, (i, got, want)
        assert np.abs(got - BACKGROUND).max() > 40
        checked += 1
    assert checked >= least, checked
    # a spot beside the UAVs is background: the pixels above are not everywhere
    empty = screen[:, :2].min(axis=0) - 25
    assert np.abs(_pixel(page, *np.clip(empty, 2, None)) - BACKGROUND).max() <= 12


def test_seek_puts_the_pairs_where_the_camera_sees_them(page, replay):
    check_screen_positions(page, replay[0], STEP, least=6)


@pytest.fixture(scope="module")
def env_replay(tmp_path_factory):
    """A replay of an env episode (4 pairs among 12 UAVs) recorded through RecordEpisode."""
    folder = tmp_path_factory.mktemp("env")
    pairs = ((0, 1), (2, 3), (4, 5), (6, 7))
    kw = dict(n_uavs=12, pairs=pairs, init="random", max_cycles=60, d_m=3.0)
    with RecordEpisode(pf.parallel_env(**kw), folder, controller="constant") as env:
        env.reset(seed=2)
        while env.agents:
            env.step({a: np.array([0.4, -0.2]) for a in env.agents})
    build_replay(env.recorder.paths[0], folder / "env.html")
    return open_recording(env.recorder.paths[0]), folder / "env.html"


def test_seek_on_an_env_recording(browser, env_replay):
    rec, html = env_replay
    page, errors = headless.open_replay(browser, html, SIZE)
    check_screen_positions(page, rec, 37, least=5)
    _hook(page, "jumpToClosest()")  # (the panels, its button among them, are hidden now)
    cp = _hook(page, "meta.closest_pass")
    assert _hook(page, "step") == cp["index"]
    assert cp["distance"] == pytest.approx(float(np.min(rec["closest_distance"])), rel=1e-6)
    assert errors == [], f"console errors: {errors}"
    page.close()


@pytest.mark.parametrize("html", DOCS_REPLAYS, ids=[p.stem for p in DOCS_REPLAYS])
def test_the_docs_replays_load_and_play(browser, html):
    page, errors = headless.open_replay(browser, html, SIZE)
    assert _hook(page, "meta.complete") and _hook(page, "meta.controller") == "smc"
    page.click("#pf-closest")
    page.evaluate("window.pairflockReplay.play({stepsPerFrame: 8})")
    page.wait_for_timeout(300)
    assert _hook(page, "playing") and _hook(page, "fps()") > 0
    assert errors == [], f"console errors: {errors}"
    page.close()


def test_scrub_play_and_speed(page, replay):
    page.eval_on_selector(
        "#pf-scrub", "e => { e.value = '40'; e.dispatchEvent(new Event('input')); }"
    )
    assert _hook(page, "step") == 40
    page.select_option("#pf-speed", "4")
    page.evaluate("document.activeElement.blur()")
    page.keyboard.press("Space")
    page.wait_for_timeout(600)
    assert _hook(page, "playing") and _hook(page, "step") > 40
    page.click("#pf-play")
    assert not _hook(page, "playing")
    assert _hook(page, "fps()") > 0


def test_closest_pass_one_click(page, replay):
    rec, _ = replay
    page.click("#pf-closest")
    cp = _hook(page, "meta.closest_pass")
    assert _hook(page, "step") == cp["index"] and _hook(page, "selected") == cp["uav"]
    assert {cp["uav"], cp["other"]} == {2, 3}
    t = rec["time"][cp["recorded_step"]]
    assert _hook(page, "time") == pytest.approx(t)


def test_pick_by_click_and_follow(page, replay):
    page.add_style_tag(content=".box { display: none !important; }")
    _hook(page, f"seek({STEP})")
    _next_frame(page)
    x, y, _ = _hook(page, "projectUav(4)")
    page.mouse.click(x, y)
    assert _hook(page, "selected") == 4
    _hook(page, "follow(true)")
    _hook(page, f"seek({STEP + 40})")
    size = _hook(page, "canvasSize()")
    x, y, _ = _hook(page, "projectUav(4)")  # the followed UAV stays in the middle
    assert abs(x - size["cssWidth"] / 2) < 1 and abs(y - size["cssHeight"] / 2) < 1


def test_loads_without_fromBase64(browser, replay):
    """Browsers without Uint8Array.fromBase64 take the atob path, to the same numbers."""
    rec, html = replay
    page, errors = headless.open_replay(
        browser, html, SIZE, init_script="delete Uint8Array.fromBase64;"
    )
    assert page.evaluate("typeof Uint8Array.fromBase64") == "undefined"
    _hook(page, "seek(77)")
    got = np.array([_hook(page, f"uavPosition({i})") for i in range(rec.num_uavs)])
    np.testing.assert_allclose(got, rec["positions"][77], atol=2e-3)
    assert errors == []
    page.close()
