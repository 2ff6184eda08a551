"""Headless Chromium driven over its DevTools pipe (no extra package, no download).

One browser process serves every page of a test session: ``Browser().check(path)`` loads a file at
1280×800 and returns what the report tests assert on (console errors, images that do not decode,
horizontal overflow, where the summary sits, tables and preformatted blocks), plus a screenshot of
the first screen. The pipe protocol: JSON messages terminated by a NUL byte, the browser reading
fd 3 and writing fd 4 (``--remote-debugging-pipe``).
"""
from __future__ import annotations

import fcntl
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

CHROMIUM = os.environ.get("CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-extensions", "--remote-debugging-pipe")
WIDTH, HEIGHT = 1280, 800
TIMEOUT_S = 30.0

# Measured in the page after load: everything the checks need, as one JSON object.
MEASURE = """(() => {
 const vh = window.innerHeight, imgs = Array.from(document.images);
 const s = document.getElementById("summary"), figs = document.querySelectorAll("figure");
 const first = (sel) => { const e = document.querySelector(sel); return e ? e.getBoundingClientRect().bottom : null; };
 return JSON.stringify({
  viewport: [window.innerWidth, vh],
  scroll_width: document.documentElement.scrollWidth,
  images: imgs.length,
  broken_images: imgs.filter(i => !i.complete || i.naturalWidth === 0).map(i => i.alt || i.src.slice(0, 40)),
  figures: figs.length,
  figures_without_image: Array.from(figs).filter(f => !f.querySelector("img")).map(f => f.id),
  tables: document.querySelectorAll("table").length,
  tables_without_header: Array.from(document.querySelectorAll("table")).filter(t => !t.querySelector("thead th")).length,
  pre: document.querySelectorAll("pre").length,
  summary: s !== null,
  summary_top: s ? s.getBoundingClientRect().top : null,
  verdict_bottom: first("#summary .verdict"),
  summary_table_bottom: first("#summary table"),
  summary_before_figures: s !== null && (figs.length === 0 ||
     (s.compareDocumentPosition(figs[0]) & Node.DOCUMENT_POSITION_FOLLOWING) !== 0),
  summary_text: s ? s.innerText : "",
  summary_cells: s ? Array.from(s.querySelectorAll("tbody tr")).map(r => Array.from(r.cells).map(c => c.textContent)) : [],
 });
})()"""


class BrowserUnavailable(RuntimeError):
    """No Chromium to run (the tests skip with this message)."""


class Browser:
    """One headless Chromium; ``check`` pages one after the other in a fresh tab each."""

    def __init__(self, executable: str = CHROMIUM):
        if not (Path(executable).is_file() and os.access(executable, os.X_OK)):
            raise BrowserUnavailable(f"no Chromium at {executable} (Debian: apt-get install -y chromium; "
                                     "or set CHROMIUM=/path/to/chromium)")
        self._profile = tempfile.mkdtemp(prefix="rx90-chromium-")
        to_browser, self._ours_w = os.pipe()
        self._ours_r, from_browser = os.pipe()

        def fds() -> None:  # in the child: the protocol's fds 3 (commands in) and 4 (replies out)
            high = [fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (to_browser, from_browser)]  # neither 3 nor 4
            os.dup2(high[0], 3)  # dup2 leaves them inheritable; Python's own fds are not (PEP 446)
            os.dup2(high[1], 4)

        self._proc = subprocess.Popen([executable, *FLAGS, f"--user-data-dir={self._profile}", "about:blank"],
                                      close_fds=False, preexec_fn=fds, stdin=subprocess.DEVNULL,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_browser)
        os.close(from_browser)
        self._buffer = b""
        self._id = 0
        self.events: list[dict] = []

    def close(self) -> None:
        try:
            self._call("Browser.close")
        except (OSError, RuntimeError, EOFError):
            pass
        try:
            self._proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()
        for fd in (self._ours_w, self._ours_r):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self) -> "Browser":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ protocol
    def _send(self, method: str, params: dict | None, session: str | None) -> int:
        self._id += 1
        message = {"id": self._id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self._ours_w, json.dumps(message).encode() + b"\0")
        return self._id

    def _receive(self, deadline: float) -> dict:
        while b"\0" not in self._buffer:
            if time.monotonic() > deadline:
                raise RuntimeError("Chromium did not answer in time")
            chunk = os.read(self._ours_r, 1 << 20)
            if not chunk:
                raise EOFError("Chromium closed its pipe")
            self._buffer += chunk
        message, _, self._buffer = self._buffer.partition(b"\0")
        return json.loads(message)

    def _call(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        wanted = self._send(method, params, session)
        deadline = time.monotonic() + TIMEOUT_S
        while True:
            message = self._receive(deadline)
            if message.get("id") == wanted:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})
            self.events.append(message)

    def _wait_event(self, name: str, session: str) -> None:
        deadline = time.monotonic() + TIMEOUT_S
        while not any(e.get("method") == name and e.get("sessionId") == session for e in self.events):
            self.events.append(self._receive(deadline))

    # ------------------------------------------------------------------ pages
    def check(self, path: str | os.PathLike, screenshot: bool = False, script: str | None = None,
              media: str = "screen", width: int = WIDTH) -> dict:
        """Load ``path`` at 1280×800; the measurements (see MEASURE), ``console_errors`` and, when
        asked, ``screenshot`` (PNG bytes of the first screen) and ``script`` (the value of a
        JavaScript expression evaluated in the page after the measurements). media: "screen" or
        "print" (the print style sheet, e.g. at width 718 px: A4 less 15 mm margins at 96 dpi)."""
        target = self._call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self._call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        self.events = []
        for domain in ("Page", "Runtime", "Log"):
            self._call(f"{domain}.enable", session=session)
        self._call("Emulation.setDeviceMetricsOverride", {"width": width, "height": HEIGHT, "deviceScaleFactor": 1,
                                                          "mobile": False}, session)
        self._call("Emulation.setEmulatedMedia", {"media": media}, session)
        self._call("Page.navigate", {"url": Path(path).resolve().as_uri()}, session)
        self._wait_event("Page.loadEventFired", session)
        value = self._call("Runtime.evaluate", {"expression": MEASURE, "returnByValue": True}, session)
        out = json.loads(value["result"]["value"])
        if script is not None:
            out["script"] = self._call("Runtime.evaluate", {"expression": script, "returnByValue": True},
                                       session)["result"].get("value")
        out["console_errors"] = _errors(self.events, session)
        if screenshot:
            import base64

            shot = self._call("Page.captureScreenshot", {"format": "png"}, session)
            out["screenshot"] = base64.b64decode(shot["data"])
        self._call("Target.closeTarget", {"targetId": target})
        return out


def _errors(events: list[dict], session: str) -> list[str]:
    """Console errors and uncaught exceptions reported by the page."""
    out = []
    for e in events:
        if e.get("sessionId") != session:
            continue
        p = e.get("params", {})
        if e.get("method") == "Runtime.exceptionThrown":
            out.append(p.get("exceptionDetails", {}).get("text", "exception"))
        elif e.get("method") == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append(" ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
        elif e.get("method") == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            out.append(p["entry"].get("text", ""))
    return out


def problems(m: dict) -> list[str]:
    """What is wrong with a report page, from :meth:`Browser.check`'s measurements ([] when nothing)."""
    out = [f"console error: {e}" for e in m["console_errors"]]
    out += [f"image does not decode: {b}" for b in m["broken_images"]]
    out += [f"figure without an image: {f}" for f in m["figures_without_image"]]
    if m["scroll_width"] > m["viewport"][0]:
        out.append(f"horizontal overflow: {m['scroll_width']} px wide at {m['viewport'][0]} px")
    if m["pre"]:
        out.append(f"{m['pre']} preformatted block(s) where tables belong")
    if m["tables_without_header"]:
        out.append(f"{m['tables_without_header']} table(s) without a header row")
    if not m["summary"]:
        out.append("no summary")
    else:
        if not m["summary_before_figures"]:
            out.append("the summary comes after a figure")
        height = m["viewport"][1]
        for key in ("verdict_bottom", "summary_table_bottom"):
            if m[key] is not None and m[key] > height:
                out.append(f"summary not in the first screen: {key} at {m[key]:.0f} px > {height} px")
    return out
