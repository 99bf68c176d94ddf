"""Replay pages in headless Chromium, driven by Playwright: screenshots, tests, fps benchmark.

Needs the Python package ``playwright`` (in the ``dev`` extra) and a Chromium: Debian's
package ``chromium`` (``apt-get install -y chromium``) is used as it is, so no
``playwright install`` download is needed. ``PAIRFLOCK_CHROMIUM`` names another binary.
WebGL2 runs on the CPU (SwiftShader through ANGLE), so no GPU is needed either.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterator
from typing import Any

try:  # optional: the dev extra's browser driver
    from playwright.sync_api import sync_playwright
except ImportError:  # the replay pages are built without it; only opening them needs it
    sync_playwright = None

__all__ = [
    "CHROMIUM_PACKAGE",
    "LAUNCH_ARGS",
    "find_chromium",
    "launch",
    "missing",
    "open_replay",
    "screenshot",
]

CHROMIUM_PACKAGE = "chromium"  # the Debian package
#: Playwright adds --headless and its own profile folder; these keep the browser off the
#: network and on software WebGL (SwiftShader), and let it run as root in a container
LAUNCH_ARGS = (
    "--no-sandbox",
    "--disable-gpu",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)
_READY = (
    "() => window.pairflockReplay && (window.pairflockReplay.loaded || "
    "!!window.pairflockReplay.error)"
)


def find_chromium() -> str | None:
    """The Chromium binary: ``$PAIRFLOCK_CHROMIUM``, else ``chromium`` on the PATH."""
    named = os.environ.get("PAIRFLOCK_CHROMIUM")
    if named:
        return named if os.access(named, os.X_OK) else None
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return None


def missing() -> str | None:
    """Why a replay cannot be opened here (a sentence naming what to install), or None."""
    needs = []
    if sync_playwright is None:
        needs.append("the Python package playwright (pip install playwright, in the dev extra)")
    if find_chromium() is None:
        needs.append(
            f"the Debian package {CHROMIUM_PACKAGE} (apt-get install -y {CHROMIUM_PACKAGE})"
        )
    return f"no browser to open a replay: install {' and '.join(needs)}" if needs else None


@contextlib.contextmanager
def launch(extra_args: tuple[str, ...] = ()) -> Iterator[Any]:
    """A headless Chromium (a Playwright ``Browser``), closed on exit."""
    reason = missing()
    if reason:
        raise RuntimeError(f"cannot open a replay: {reason}")
    with sync_playwright() as pw:
        browser = pw.chromium.launch(
            executable_path=find_chromium(), args=[*LAUNCH_ARGS, *extra_args]
        )
        try:
            yield browser
        finally:
            browser.close()


def open_replay(
    browser: Any,
    html: str | os.PathLike,
    size: tuple[int, int] = (1280, 720),
    timeout_s: float = 60,
    init_script: str | None = None,
) -> tuple[Any, list[str]]:
    """Open the replay page ``html`` in a new page of ``size`` pixels (running
    ``init_script`` first, if given) and wait until it has loaded its data; return the page
    and the list that collects its console errors."""
    page = browser.new_page(viewport={"width": size[0], "height": size[1]})
    if init_script:
        page.add_init_script(init_script)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda exc: errors.append(f"uncaught: {exc}"))
    page.goto("file://" + os.path.abspath(html))
    page.wait_for_function(_READY, timeout=timeout_s * 1000)
    failure = page.evaluate("window.pairflockReplay.error")
    if failure:
        raise RuntimeError(f"the replay page failed to load: {failure}")
    return page, errors


def screenshot(
    html: str | os.PathLike,
    png: str | os.PathLike,
    step: int | None = None,
    size: tuple[int, int] = (1280, 720),
) -> None:
    """Save a screenshot of the replay page ``html`` at replayed step ``step`` (default:
    the closest pass if there is one, else the first step)."""
    with launch() as browser:
        page, _ = open_replay(browser, html, size)
        if step is None:
            page.evaluate("window.pairflockReplay.jumpToClosest()")
        else:
            page.evaluate(f"window.pairflockReplay.seek({int(step)})")
        page.wait_for_timeout(200)
        page.screenshot(path=os.fspath(png))
