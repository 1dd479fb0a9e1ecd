"""Headless Chromium (Debian's /usr/bin/chromium) driven over the DevTools protocol, for the
tests of the HTML pages.

The protocol runs over a pipe (--remote-debugging-pipe: Chromium reads requests from fd 3
and writes replies to fd 4, each a JSON message ended by a NUL byte), so no driver package
and no browser download is needed: only the Debian package that `make deps` installs. The
flags keep Chromium from opening any connection of its own (it runs as root in a closed
network here and in CI)."""

from __future__ import annotations

import base64
import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--disable-dev-shm-usage",
    "--remote-debugging-pipe",
]
INSTALL_HINT = "Debian's chromium package, installed by `make deps` (apt-get install chromium)"


def executable() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


class ProtocolError(RuntimeError):
    pass


class Browser:
    """One Chromium process; `call` sends a protocol command and waits for its reply while
    the events that arrive meanwhile are kept in `events`."""

    def __init__(self, path: str):
        self.profile = tempfile.mkdtemp(prefix="accelbench-chromium-")
        # Chromium's own messages (D-Bus is absent here and says so at length) go to a file,
        # read back only when it dies.
        self._log = open(os.path.join(self.profile, "stderr.log"), "wb")
        to_child_r, self._to_child = os.pipe()
        self._from_child, from_child_w = os.pipe()

        def child_fds() -> None:  # the pipe's ends at fd 3 (requests) and fd 4 (replies)
            # to_child_r < from_child_w (made first), so the first dup2 cannot clobber the
            # second's source; an end already at its number only needs to survive exec.
            for src, dst in ((to_child_r, 3), (from_child_w, 4)):
                if src == dst:
                    os.set_inheritable(dst, True)
                else:
                    os.dup2(src, dst)

        self.proc = subprocess.Popen(
            [path, *FLAGS, f"--user-data-dir={self.profile}", "about:blank"],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=self._log,
            preexec_fn=child_fds,
            close_fds=False,
        )
        os.close(to_child_r)
        os.close(from_child_w)
        self._next_id = 0
        self._replies: queue.Queue = queue.Queue()
        self.events: list[dict] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        buf = b""
        while True:
            chunk = os.read(self._from_child, 1 << 16)
            if not chunk:
                self._replies.put(None)
                return
            buf += chunk
            while b"\0" in buf:
                raw, buf = buf.split(b"\0", 1)
                msg = json.loads(raw)
                if "id" in msg:
                    self._replies.put(msg)
                else:
                    self.events.append(msg)

    def call(self, method: str, params: dict | None = None, session: str | None = None, timeout: float = 60):
        self._next_id += 1
        msg = {"id": self._next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self._to_child, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            try:
                reply = self._replies.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                raise ProtocolError(f"{method}: no reply within {timeout} s") from None
            if reply is None:
                raise ProtocolError(f"{method}: Chromium closed the pipe ({self.log_tail()})")
            if reply["id"] == self._next_id:
                if "error" in reply:
                    raise ProtocolError(f"{method}: {reply['error']}")
                return reply.get("result", {})

    def log_tail(self) -> str:
        lines = Path(self._log.name).read_text(errors="replace").splitlines()
        return "\n".join(line for line in lines if "dbus" not in line)[-2000:]

    def close(self) -> None:
        try:
            self.call("Browser.close", timeout=10)
        except ProtocolError:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        for fd in (self._to_child, self._from_child):
            try:
                os.close(fd)
            except OSError:
                pass
        self._log.close()
        shutil.rmtree(self.profile, ignore_errors=True)


@dataclass
class Rendered:
    """What a page did in the browser."""

    errors: list[str] = field(default_factory=list)  # console errors, exceptions, failed loads
    requests: list[str] = field(default_factory=list)  # every URL the page asked for
    facts: dict = field(default_factory=dict)  # the value of the `probe` expression
    screenshot: bytes = b""  # PNG


def _console_errors(events: list[dict]) -> list[str]:
    out = []
    for e in events:
        method, p = e.get("method"), e.get("params", {})
        if method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append(
                "console: " + " ".join(str(a.get("value", a.get("description", ""))) for a in p["args"])
            )
        elif method == "Runtime.exceptionThrown":
            d = p["exceptionDetails"]
            out.append("exception: " + d.get("exception", {}).get("description", d.get("text", "")))
        elif method == "Log.entryAdded" and p["entry"]["level"] == "error":
            out.append(f"log ({p['entry'].get('source')}): {p['entry']['text']}")
        elif method == "Network.loadingFailed":
            out.append(f"load failed: {p.get('errorText')} ({p.get('requestId')})")
    return out


def render(page: Path, probe: str, width: int = 1400, height: int = 1000, timeout: float = 60) -> Rendered:
    """Opens `page` from file://, waits until its figures are drawn (or failed), evaluates
    the JavaScript expression `probe` (its value must be JSON) and takes a screenshot of
    the first screen."""
    path = executable()
    if path is None:
        raise FileNotFoundError(f"no chromium: {INSTALL_HINT}")
    browser = Browser(path)
    try:
        target = browser.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = browser.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Runtime", "Log", "Network", "Page"):
            browser.call(f"{domain}.enable", session=session)
        browser.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
            session=session,
        )
        browser.call("Page.navigate", {"url": page.resolve().as_uri()}, session=session)
        state = "pending"
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            state = browser.call(
                "Runtime.evaluate",
                {
                    "expression": "document.readyState === 'complete' && document.documentElement.dataset.charts",
                    "returnByValue": True,
                },
                session=session,
            )["result"].get("value")
            if state in ("ready", "failed"):
                break
            time.sleep(0.2)
        out = Rendered()
        out.facts = browser.call(
            "Runtime.evaluate", {"expression": probe, "returnByValue": True}, session=session
        )["result"].get("value", {})
        out.facts["charts"] = state
        shot = browser.call("Page.captureScreenshot", {"format": "png"}, session=session)
        out.screenshot = base64.b64decode(shot["data"])
        out.errors = _console_errors(browser.events)
        out.requests = [
            e["params"]["request"]["url"]
            for e in browser.events
            if e.get("method") == "Network.requestWillBeSent"
        ]
        return out
    finally:
        browser.close()
