# SPDX-License-Identifier: Apache-2.0
"""What the browser tests of the web view share: a free port, polling, the JSON endpoints, and a
short simulator recording served by `tacse3-replay --view`."""
import contextlib
import json
import os
import shutil
import socket
import subprocess
import tempfile
import time
import urllib.request

SKIP = 77  # ctest's SKIP_RETURN_CODE for these tests


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(what, fn, timeout_s, poll_s=0.05):
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        value = fn()
        if value:
            return value
        time.sleep(poll_s)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


def chromium_missing():
    """Why headless Chromium cannot run here (to print before exiting SKIP), or None."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        selenium = None
    if shutil.which("chromium") and shutil.which("chromedriver") and selenium is not None:
        return None
    return ("browser test skipped: needs Debian's chromium, chromium-driver and python3-selenium "
            "(scripts/setup.sh installs them)")


def headless_chromium(window_height):
    """Debian's chromium under chromedriver, headless, 1500 px wide."""
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    opts = Options()
    opts.binary_location = shutil.which("chromium")
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu",
              f"--window-size=1500,{window_height}", "--disable-dev-shm-usage"):
        opts.add_argument(a)
    return webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)


def get_json(url, timeout_s=1):
    """The endpoint's JSON, or None while the server is not up."""
    try:
        with urllib.request.urlopen(url, timeout=timeout_s) as r:
            return json.loads(r.read())
    except OSError:
        return None


@contextlib.contextmanager
def served_recording(sim, replay, log_path, prefix):
    """Renders 1.5 s at 120 Hz (the sphere turns 20 degrees about z in 0.5 s, docs/simulator.md)
    and serves it with `tacse3-replay --view`. Yields (recording dir, base URL, /api/info).
    On the way out the replay must exit 0 on SIGTERM."""
    tmp = tempfile.mkdtemp(prefix=prefix)
    rec = os.path.join(tmp, "rec")
    subprocess.run([sim, "-o", rec, "--magnitude", "20", "--motion-s", "0.5", "-q"], check=True)
    base = f"http://127.0.0.1:{free_port()}"
    log = open(log_path, "w")
    proc = subprocess.Popen([replay, rec, "--out", os.path.join(tmp, "out.csv"), "-q", "--view",
                             base[len("http://"):]], stdout=log, stderr=log)
    try:
        info = wait_for("/api/info", lambda: get_json(base + "/api/info"), 30)
        yield rec, base, info
    finally:
        proc.terminate()
        rc = proc.wait(timeout=20)
        log.close()
        shutil.rmtree(tmp, ignore_errors=True)
    if rc != 0:
        raise AssertionError(f"tacse3-replay --view exited {rc} on SIGTERM (expected 0)")
