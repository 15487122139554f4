"""A page rendered in a real headless Chromium, driven over the DevTools protocol (test
helper): console errors and uncaught exceptions, images that did not decode, and a
screenshot.

Chromium comes from the system (Debian's ``chromium`` package; ``.ci/run`` installs it
when absent); the protocol goes over a websocket (``websocket-client``, a test extra).
"""

from __future__ import annotations

import io
import json
import os
import re
import shutil
import socket
import subprocess
import tempfile
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def find_chromium() -> str | None:
    """The Chromium executable on PATH (None when absent)."""
    return next((p for p in map(shutil.which, BROWSERS) if p), None)


@dataclass
class PageCheck:
    """What the browser saw of one page."""

    title: str
    images: int
    broken_images: list[str]
    console_errors: list[str] = field(default_factory=list)
    screenshot_png: bytes = b""
    sections: int = 0
    #: the page's visible text (``document.body.innerText``)
    text: str = ""
    #: page-coordinate boxes (``x, y, width, height``) of the timeline's event labels
    #: and of its drawing (None: no timeline)
    label_boxes: list[dict] = field(default_factory=list)
    timeline_box: dict | None = None


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class _Session:
    def __init__(self, ws_url: str, timeout: float) -> None:
        import websocket

        self.ws = websocket.create_connection(ws_url, timeout=timeout, suppress_origin=True)
        self.next_id = 0
        self.events: list[dict] = []

    def call(self, method: str, **params) -> dict:
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == self.next_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            self.events.append(msg)

    def wait_for(self, method: str, timeout: float) -> None:
        end = time.monotonic() + timeout
        if any(e.get("method") == method for e in self.events):
            return
        while time.monotonic() < end:
            msg = json.loads(self.ws.recv())
            self.events.append(msg)
            if msg.get("method") == method:
                return
        raise TimeoutError(f"no {method} within {timeout} s")


def _errors(events: list[dict]) -> list[str]:
    out = []
    for e in events:
        m, p = e.get("method"), e.get("params", {})
        if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append("console." + p["type"] + ": " + " ".join(str(a.get("value", a.get("description", "")))
                                                                for a in p.get("args", [])))
        elif m == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            out.append("exception: " + str(d.get("exception", {}).get("description", d.get("text", ""))))
        elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            out.append("log: " + p["entry"].get("text", ""))
    return out


def check_page(path: Path, width: int = 1366, height: int = 900, timeout: float = 60.0,
               anchor: str = "", scale: float = 1.0) -> PageCheck:
    """Load ``path`` (a local HTML file) in headless Chromium at a laptop's viewport and
    report what it saw; ``anchor`` scrolls the screenshot to ``#anchor``; ``scale``
    shrinks the screenshot (0.5: half the pixels each way).

    Raises
    ------
    RuntimeError
        No Chromium, or it would not start.
    """
    exe = find_chromium()
    if exe is None:
        raise RuntimeError("no Chromium on PATH (apt-get install chromium)")
    port = _free_port()
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        proc = subprocess.Popen([exe, "--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run",
                                 "--disable-extensions", "--hide-scrollbars", f"--window-size={width},{height}",
                                 f"--remote-debugging-port={port}", "--remote-allow-origins=*",
                                 f"--user-data-dir={profile}", "about:blank"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=dict(os.environ))
        try:
            end = time.monotonic() + timeout
            targets = None
            while time.monotonic() < end:
                try:
                    with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=2) as r:
                        targets = [t for t in json.loads(r.read()) if t.get("type") == "page"]
                    if targets:
                        break
                except OSError:
                    pass
                if proc.poll() is not None:
                    raise RuntimeError(f"Chromium exited with {proc.returncode}")
                time.sleep(0.2)
            if not targets:
                raise RuntimeError("Chromium's DevTools endpoint did not come up")
            s = _Session(targets[0]["webSocketDebuggerUrl"], timeout)
            for domain in ("Runtime", "Log", "Page"):
                s.call(f"{domain}.enable")
            s.call("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1, mobile=False)
            s.call("Page.navigate", url=Path(path).resolve().as_uri() + (f"#{anchor}" if anchor else ""))
            s.wait_for("Page.loadEventFired", timeout)
            probe = ("JSON.stringify({title: document.title, n: document.images.length, sections: "
                     "document.querySelectorAll('section').length, broken: Array.from(document.images)"
                     ".filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.alt || i.src.slice(0, 40))})")
            seen = json.loads(s.call("Runtime.evaluate", expression=probe, returnByValue=True)["result"]["value"])
            boxes = ("JSON.stringify({text: document.body.innerText, labels: Array.from(document.querySelectorAll("
                     "'svg[aria-label=\"events timeline\"] text.event-label')).map(e => {const r = "
                     "e.getBoundingClientRect(); return {text: e.textContent, x: r.x + scrollX, y: r.y + scrollY, "
                     "width: r.width, height: r.height};}), svg: (() => {const e = document.querySelector("
                     "'svg[aria-label=\"events timeline\"]'); if (!e) return null; const r = "
                     "e.getBoundingClientRect(); return {x: r.x + scrollX, y: r.y + scrollY, width: r.width, "
                     "height: r.height};})()})")
            dom = json.loads(s.call("Runtime.evaluate", expression=boxes, returnByValue=True)["result"]["value"])
            import base64

            shot_args: dict = {"format": "png"}
            if scale != 1.0:
                metrics = s.call("Page.getLayoutMetrics")["cssVisualViewport"]
                shot_args["clip"] = {"x": metrics["pageX"], "y": metrics["pageY"], "width": width, "height": height,
                                     "scale": scale}
            shot = base64.b64decode(s.call("Page.captureScreenshot", **shot_args)["data"])
            time.sleep(0.2)  # late console messages
            s.ws.settimeout(0.3)
            try:
                while True:
                    s.events.append(json.loads(s.ws.recv()))
            except Exception:  # noqa: BLE001 - the socket's timeout ends the drain
                pass
            s.ws.close()
            return PageCheck(title=seen["title"], images=seen["n"], broken_images=seen["broken"],
                             console_errors=_errors(s.events), screenshot_png=shot, sections=seen["sections"],
                             text=dom["text"], label_boxes=dom["labels"], timeline_box=dom["svg"])
        finally:
            proc.terminate()
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()


def is_blank(png: bytes) -> bool:
    """True when a screenshot is one flat colour (nothing rendered): fewer than 16
    distinct grey levels, or a standard deviation below 2 of 255."""
    from matplotlib.image import imread

    img = imread(io.BytesIO(png), format="png")[..., :3]
    grey = (img.mean(axis=2) * 255).round()
    return len(np.unique(grey)) < 16 or float(grey.std()) < 2.0


def overlapping_labels(boxes: list[dict], gap: float = 0.0) -> list[tuple[str, str]]:
    """Pairs of label boxes that overlap (closer than ``gap`` px), by their text."""
    out = []
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            if (a["x"] < b["x"] + b["width"] + gap and b["x"] < a["x"] + a["width"] + gap
                    and a["y"] < b["y"] + b["height"] and b["y"] < a["y"] + a["height"]):
                out.append((a["text"], b["text"]))
    return out


def clipped_labels(boxes: list[dict], frame: dict) -> list[str]:
    """Labels whose box leaves ``frame`` (the timeline's drawing), by their text."""
    return [b["text"] for b in boxes
            if b["x"] < frame["x"] - 0.5 or b["y"] < frame["y"] - 0.5
            or b["x"] + b["width"] > frame["x"] + frame["width"] + 0.5
            or b["y"] + b["height"] > frame["y"] + frame["height"] + 0.5]


def require_chromium() -> None:
    """Skip the calling test when no Chromium is on PATH, or fail it when
    ``SAVANT_REQUIRE_CHROMIUM=1`` (CI) says there must be one."""
    import pytest

    if find_chromium() is None:
        if os.environ.get("SAVANT_REQUIRE_CHROMIUM") == "1":
            pytest.fail("SAVANT_REQUIRE_CHROMIUM=1 but no Chromium on PATH")
        pytest.skip("no Chromium on PATH (apt-get install chromium)")


def assert_page_reads(run_dir: Path) -> None:
    """The Chromium checks of a study's ``report.html`` as a reviewer reads it: no console
    error or broken image, no dict text, no float noise (such as 7.47999999999997),
    timeline labels apart and inside the drawing."""
    seen = check_page(Path(run_dir) / "report.html")
    assert seen.console_errors == [] and seen.broken_images == []
    assert "{" not in seen.text and "}" not in seen.text, seen.text[max(seen.text.find("{") - 80, 0):][:200]
    assert not re.search(r"\d\.\d*(9999|0000)\d", seen.text)
    assert overlapping_labels(seen.label_boxes, gap=2.0) == []
    if seen.timeline_box is not None:
        assert clipped_labels(seen.label_boxes, seen.timeline_box) == []


if __name__ == "__main__":  # python tests/browser.py REPORT.html SHOT.png [ANCHOR [SCALE]]: the docs' screenshots
    import sys

    seen = check_page(Path(sys.argv[1]), anchor=sys.argv[3] if len(sys.argv) > 3 else "",
                      scale=float(sys.argv[4]) if len(sys.argv) > 4 else 1.0)
    Path(sys.argv[2]).write_bytes(seen.screenshot_png)
    print(f"{sys.argv[2]}: {seen.images} images, broken {seen.broken_images}, console errors {seen.console_errors}")
