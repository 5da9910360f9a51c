#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tacse3-replay --view in headless Firefox (Debian's firefox-esr, driven over Marionette by
libfirefox-marionette-perl: Debian has no geckodriver).

Renders the recording of replay_browser_test.py, serves it and runs firefox_check.pl on the page
(frame 0 with every plot, the scrubber moving the readouts, the image and the 3D view), which
saves --screenshot. Exit 77 (ctest: skipped) when Firefox or the Perl module is missing.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import urllib.request

from replay_browser_test import free_port, wait_for

SKIP = 77


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sim", required=True)
    ap.add_argument("--replay", required=True)
    ap.add_argument("--screenshot", required=True)
    args = ap.parse_args()
    has_module = subprocess.run(["perl", "-MFirefox::Marionette", "-e", "1"],
                                capture_output=True).returncode == 0
    if not shutil.which("firefox-esr") or not has_module:
        print("Firefox test skipped: needs Debian's firefox-esr and libfirefox-marionette-perl "
              "(scripts/setup.sh installs them)")
        return SKIP

    tmp = tempfile.mkdtemp(prefix="tacse3-replay-firefox-")
    rec = os.path.join(tmp, "rec")
    subprocess.run([args.sim, "-o", rec, "--magnitude", "20", "--motion-s", "0.5", "-q"],
                   check=True)
    port = free_port()
    url = f"http://127.0.0.1:{port}/"
    log = open(args.screenshot + ".replay.log", "w")
    replay = subprocess.Popen([args.replay, rec, "--out", os.path.join(tmp, "out.csv"), "-q",
                               "--view", f"127.0.0.1:{port}"], stdout=log, stderr=log)
    try:
        def info():
            try:
                return json.loads(urllib.request.urlopen(url + "api/info", timeout=1).read())
            except OSError:
                return None
        wait_for("/api/info", info, 30)
        check = os.path.join(os.path.dirname(os.path.abspath(__file__)), "firefox_check.pl")
        # Firefox wants a writable home for its profile; a fresh one keeps runs independent.
        env = dict(os.environ, HOME=os.path.join(tmp, "home"))
        os.makedirs(env["HOME"])
        rc = subprocess.run(["perl", check, url, args.screenshot], env=env, timeout=240).returncode
        print(f"screenshot: {args.screenshot}" if rc == 0 else f"firefox_check.pl exited {rc}")
        return 0 if rc == 0 else 1
    finally:
        replay.terminate()
        replay.wait(timeout=20)
        log.close()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
