"""A real headless Chromium for the tests of pages ftcal writes (the calibration report).

``.ci/run`` installs Debian's ``chromium``. :func:`render` loads a page from a file, as a user opening it
would, and returns what the page did: its console messages (Chromium's ``--enable-logging`` writes each
``console.*`` call and uncaught error as a ``CONSOLE`` line), the network requests *the page* made (from
Chromium's net log: requests whose network-isolation key is the page's ``file://`` origin; the browser's
own background requests carry other keys), and the DOM after load.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

#: Flags of a quiet, sandbox-less headless Chromium (as root in CI) that opens nothing by itself.
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync")


def chromium() -> str:
    """Path of the Chromium binary; a clear failure (not a skip) when it is missing."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    raise AssertionError("no Chromium found: install the Debian package 'chromium' (apt-get install chromium), "
                         "as .ci/run does")


@dataclass
class Rendered:
    console: list[str]
    page_requests: list[str]
    dom: str


def _run(args: list[str], work: Path) -> subprocess.CompletedProcess:
    return subprocess.run([chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={work / 'profile'}", *args],
                          capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)


def render(page: Path, work: Path) -> Rendered:
    """Load ``page`` in headless Chromium; report its console messages, its own requests and its DOM."""
    work.mkdir(parents=True, exist_ok=True)
    net_log = work / "net.json"
    done = _run(["--enable-logging=stderr", "--v=0", f"--log-net-log={net_log}", "--dump-dom",
                 page.resolve().as_uri()], work)
    assert done.returncode == 0, done.stderr[-2000:]
    console = [line for line in done.stderr.splitlines() if re.search(r":CONSOLE[:(]", line)]
    text = net_log.read_text(encoding="utf-8").rstrip()
    try:
        log = json.loads(text)
    except json.JSONDecodeError:  # a net log cut at exit lacks its closing brackets
        log = json.loads(text.rstrip(",") + "]}")
    start_job = log["constants"]["logEventTypes"]["URL_REQUEST_START_JOB"]
    requests = []
    for event in log["events"]:
        params = event.get("params", {})
        if event["type"] == start_job and "file://" in str(params.get("network_isolation_key", "")):
            if not params.get("url", "").startswith(("file:", "data:")):
                requests.append(params["url"])
    return Rendered(console=console, page_requests=requests, dom=done.stdout)


def print_pdf(page: Path, pdf: Path, work: Path) -> Path:
    """Print ``page`` to ``pdf`` through the same browser."""
    done = _run([f"--print-to-pdf={pdf.resolve()}", "--no-pdf-header-footer", page.resolve().as_uri()], work)
    assert done.returncode == 0, done.stderr[-2000:]
    return pdf


def screenshot(page: Path, png: Path, work: Path, size: str = "1200,3000") -> Path:
    """A PNG of ``page`` as the browser draws it."""
    done = _run([f"--screenshot={png.resolve()}", f"--window-size={size}", page.resolve().as_uri()], work)
    assert done.returncode == 0, done.stderr[-2000:]
    return png
