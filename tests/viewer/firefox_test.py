#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tacse3-replay --view in headless Firefox (Debian's firefox-esr, driven over Marionette by
libfirefox-marionette-perl: Debian has no geckodriver).

Renders the recording of replay_browser_test.py, serves it and runs firefox_check.pl on the page
(frame 0 with every plot, the scrubber moving the readouts, the image and the 3D view), which
saves --screenshot. Exit 77 (ctest: skipped) when Firefox or the Perl module is missing.
"""
import argparse
import os
import shutil
import subprocess
import sys

from viewer_support import SKIP, served_recording


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

    with served_recording(args.sim, args.replay, args.screenshot + ".replay.log",
                          "tacse3-replay-firefox-") as (rec, base, _):
        check = os.path.join(os.path.dirname(os.path.abspath(__file__)), "firefox_check.pl")
        # Firefox wants a writable home for its profile; a fresh one keeps runs independent.
        env = dict(os.environ, HOME=os.path.join(os.path.dirname(rec), "home"))
        os.makedirs(env["HOME"])
        rc = subprocess.run(["perl", check, base + "/", args.screenshot], env=env,
                            timeout=240).returncode
    print(f"screenshot: {args.screenshot}" if rc == 0 else f"firefox_check.pl exited {rc}")
    return 0 if rc == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
