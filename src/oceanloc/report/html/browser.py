"""Load a report in headless Chromium with the network off, through the DevTools protocol (CDP).

Used by the browser tests and the report benchmark: :func:`load_page` starts Chromium (the
distribution's ``/usr/bin/chromium``) on a free loopback debugging port with a throw-away profile,
a dead proxy (``127.0.0.1:9``) and CDP ``Network.emulateNetworkConditions(offline)``, opens the file, and
returns the console errors, uncaught exceptions, every request that was not ``file:``/``data:``/``blob:``
(none is allowed), failed requests, the load time, the result of a JavaScript expression evaluated in
the page, and a PNG screenshot. Needs the PyPI package ``websocket-client``.

A page served on loopback (the live page, an ``http://127.0.0.1:PORT/`` address) is loaded the same way
except that requests to that one origin go through (the proxy is bypassed for its host and port only,
and no offline emulation); any request elsewhere still counts as an outside request and fails at the
dead proxy. ``actions`` run after the load, each followed by a wait for its own readiness expression:
the live page test appends records to the journal and waits for them to be drawn.
"""

from __future__ import annotations

import base64
import contextlib
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
import urllib.parse
import urllib.request
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

CHROMIUM_CANDIDATES = ("/usr/bin/chromium", "/usr/bin/chromium-browser", "chromium", "chromium-browser")
LOCAL_SCHEMES = ("file:", "data:", "blob:", "about:")
PLOTLY_READY = (
    "document.querySelectorAll('.plotly-graph-div').length > 0 && Array.from("
    "document.querySelectorAll('.plotly-graph-div')).every("
    "d => d._fullLayout && d.querySelector('.main-svg'))"
)
"""True once every plotly figure of a report page is drawn (the end of a load)."""


def find_chromium() -> str | None:
    """The Chromium executable, or None."""
    for c in CHROMIUM_CANDIDATES:
        found = shutil.which(c)
        if found:
            return found
    return None


@dataclass(frozen=True, slots=True, kw_only=True)
class PageLoad:
    """What a page did when loaded offline.

    Attributes
    ----------
    console_errors : list of str
        Console messages of level error, log entries of level error, and uncaught exceptions.
    outside_requests : list of str
        URLs requested that are not local (file, data, blob, about).
    failed_requests : list of str
        Requests that failed (``Network.loadingFailed``).
    load_s : float
        From navigation to the ``load`` event plus the evaluated readiness (seconds).
    value : Any
        The value of the JavaScript expression.
    screenshot_png : bytes
    action_s : list of float
        For each action, from its start to its readiness expression being true (seconds).
    """

    console_errors: list[str]
    outside_requests: list[str]
    failed_requests: list[str]
    load_s: float
    value: Any
    screenshot_png: bytes
    action_s: list[float] = field(default_factory=list)


class _Cdp:
    def __init__(self, ws_url: str, timeout_s: float) -> None:
        import websocket  # websocket-client, only needed here

        self.ws = websocket.create_connection(ws_url, timeout=timeout_s, suppress_origin=True)
        self.next_id = 0
        self.events: list[dict] = []

    def call(self, method: str, **params: Any) -> dict:
        self.next_id += 1
        my_id = self.next_id
        self.ws.send(json.dumps({"id": my_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == my_id:
                if "error" in msg:
                    raise RuntimeError(f"CDP {method}: {msg['error']}")
                return msg.get("result", {})
            if "method" in msg:
                self.events.append(msg)

    def wait_event(self, method: str, deadline: float) -> dict | None:
        for e in self.events:
            if e["method"] == method:
                return e
        while time.monotonic() < deadline:
            msg = json.loads(self.ws.recv())
            if "method" in msg:
                self.events.append(msg)
                if msg["method"] == method:
                    return msg
        return None

    def close(self) -> None:
        self.ws.close()


def _devtools_port(profile: Path, proc: subprocess.Popen, deadline: float) -> int:
    marker = profile / "DevToolsActivePort"
    while time.monotonic() < deadline:
        if marker.is_file():
            text = marker.read_text().split()
            if text:
                return int(text[0])
        if proc.poll() is not None:
            raise RuntimeError(f"chromium exited with status {proc.returncode}")
        time.sleep(0.05)
    raise RuntimeError("chromium did not open its DevTools port in time")


def load_page(
    page: str | Path,
    expression: str = "null",
    *,
    ready: str = "true",
    width: int = 1280,
    height: int = 2400,
    timeout_s: float = 30.0,
    chromium: str | None = None,
    actions: Sequence[tuple[Callable[[], object], str]] = (),
) -> PageLoad:
    """Open ``page`` offline in headless Chromium; evaluate ``expression`` once ``ready`` is true.

    ``page`` is a file, or an ``http://`` address on loopback (only its origin is reachable). Each of
    ``actions`` is ``(call, ready)``: ``call()`` runs after the load, then ``ready`` is waited for.

    Raises
    ------
    RuntimeError
        If Chromium is missing, does not start, or the page does not load within ``timeout_s``.
    """
    exe = chromium or find_chromium()
    if exe is None:
        raise RuntimeError("chromium not found (Debian: apt-get install chromium)")
    deadline = time.monotonic() + timeout_s
    # Chromium's helper processes can still write to the profile for a moment after it exits: the whole
    # process group is ended below, and a straggler's file never turns a finished load into an error.
    with tempfile.TemporaryDirectory(prefix="oceanloc-chromium-", ignore_cleanup_errors=True) as tmp:
        profile = Path(tmp)
        url = str(page) if str(page).startswith("http://") else Path(page).resolve().as_uri()
        served = urllib.parse.urlsplit(url)
        origin = f"{served.scheme}://{served.netloc}" if served.scheme == "http" else None
        bypass = "<-loopback>" if origin is None else f"<-loopback>;{served.hostname}:{served.port}"
        args = [
            exe,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--disable-default-apps",
            "--disable-extensions",
            "--proxy-server=127.0.0.1:9",
            f"--proxy-bypass-list={bypass}",
            f"--user-data-dir={profile}",
            "--remote-debugging-address=127.0.0.1",
            "--remote-debugging-port=0",
            f"--window-size={width},{height}",
            "about:blank",
        ]
        proc = subprocess.Popen(
            args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
        )
        try:
            port = _devtools_port(profile, proc, deadline)
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5) as r:
                targets = json.loads(r.read())
            target = next(t for t in targets if t.get("type") == "page")
            cdp = _Cdp(target["webSocketDebuggerUrl"], timeout_s)
            try:
                return _drive(cdp, url, expression, ready, deadline, origin, actions)
            finally:
                cdp.close()
        finally:
            _end_group(proc)


def _end_group(proc: subprocess.Popen) -> None:
    """Terminate Chromium and every helper process it started (its own session), then reap it."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, sig)
        try:
            proc.wait(timeout=5)
            return
        except subprocess.TimeoutExpired:
            continue


def _wait_true(cdp: _Cdp, url: str, ready: str, deadline: float) -> None:
    while True:
        ok = cdp.call("Runtime.evaluate", expression=f"Boolean({ready})", returnByValue=True)
        if ok.get("result", {}).get("value") is True:
            return
        if time.monotonic() > deadline:
            raise RuntimeError(f"{url}: page not ready in time ({ready})")
        time.sleep(0.02)


def _drive(
    cdp: _Cdp,
    url: str,
    expression: str,
    ready: str,
    deadline: float,
    origin: str | None,
    actions: Sequence[tuple[Callable[[], object], str]],
) -> PageLoad:
    for domain in ("Page", "Runtime", "Log", "Network"):
        cdp.call(f"{domain}.enable")
    if origin is None:  # a file: nothing at all may be fetched
        cdp.call(
            "Network.emulateNetworkConditions",
            offline=True,
            latency=0,
            downloadThroughput=-1,
            uploadThroughput=-1,
        )
    cdp.events.clear()
    t0 = time.monotonic()
    cdp.call("Page.navigate", url=url)
    if cdp.wait_event("Page.loadEventFired", deadline) is None:
        raise RuntimeError(f"{url}: no load event in time")
    _wait_true(cdp, url, ready, deadline)
    load_s = time.monotonic() - t0
    action_s = []
    for call, then_ready in actions:
        t1 = time.monotonic()
        call()
        _wait_true(cdp, url, then_ready, deadline)
        action_s.append(time.monotonic() - t1)
    value = cdp.call("Runtime.evaluate", expression=expression, returnByValue=True).get("result", {})
    shot = cdp.call("Page.captureScreenshot", format="png", captureBeyondViewport=False)
    errors, outside, failed = [], [], []
    for e in cdp.events:
        m, p = e["method"], e.get("params", {})
        if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            errors.append(" ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
        elif m == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            errors.append(str(d.get("exception", {}).get("description", d.get("text", "exception"))))
        elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            errors.append(p["entry"].get("text", ""))
        elif m == "Network.requestWillBeSent":
            u = p.get("request", {}).get("url", "")
            if not u.startswith(LOCAL_SCHEMES) and not (origin and u.startswith(origin + "/")):
                outside.append(u)
        elif m == "Network.loadingFailed":
            failed.append(f"{p.get('errorText', '')} {p.get('requestId', '')}")
    return PageLoad(
        console_errors=errors,
        outside_requests=outside,
        failed_requests=failed,
        load_s=load_s,
        value=value.get("value"),
        screenshot_png=base64.b64decode(shot["data"]),
        action_s=action_s,
    )
