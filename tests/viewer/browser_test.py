#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tacse3d's live view in headless Chromium (Debian's chromium, chromium-driver, python3-selenium).

Starts tacse3d --board BOARD --http 127.0.0.1:PORT with the board's [viewer] controls on, loads
the page and checks that the stream is live, the plots move, both pad canvases show an image (not
blank), the left pad reads OK, the pose readout and the 3D view's end points match /api/state on
the same cycle, and that the tare button is answered with an ACK shown on the page and restarts
the pose. Saves a screenshot (before the tare) to --screenshot.
Exit 77 (ctest: skipped) with a message when Chromium, its driver or selenium is missing.
"""
import argparse
import math
import os
import subprocess
import sys
import time

from pose3d_check import check_pose3d
from viewer_support import (SKIP, chromium_missing, free_port, get_json, headless_chromium,
                            wait_for)

# Standard deviation of a canvas's luma (the image with its overlays), computed in the page.
CANVAS_SD = """
const c = document.querySelector('#pad-' + arguments[0] + ' canvas');
const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
let s = 0, s2 = 0, n = d.length / 4;
for (let i = 0; i < d.length; i += 4) {
  const y = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
  s += y; s2 += y * y;
}
const m = s / n;
return Math.sqrt(Math.max(0, s2 / n - m * m));
"""


# Whether the 3D view's canvas has a strongly red pixel (the x axes).
CANVAS_HAS_RED = """
const c = document.getElementById('pose3d');
const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
for (let i = 0; i < d.length; i += 4) {
  if (d[i + 3] > 200 && d[i] > 180 && d[i + 1] < 90 && d[i + 2] < 90) return true;
}
return false;
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tacse3d", required=True)
    ap.add_argument("--board", required=True, help="the sim board.toml (looped here)")
    ap.add_argument("--calibration", required=True)
    ap.add_argument("--screenshot", required=True)
    args = ap.parse_args()

    missing = chromium_missing()
    if missing:
        print(missing)
        return SKIP

    # The sim board looping its scenario, so the plots keep moving however long the browser takes.
    board = args.screenshot + ".board.toml"
    with open(args.board) as f:
        text = f.read()
    assert "repeat = false" in text, f"{args.board}: no 'repeat = false' to turn on"
    assert "[viewer]" not in text, f"{args.board}: has a [viewer] table already"
    with open(board, "w") as f:
        f.write(text.replace("repeat = false", "repeat = true") + "\n[viewer]\ncontrols = true\n")

    port = free_port()
    base = f"http://127.0.0.1:{port}"
    log = open(args.screenshot + ".tacse3d.log", "w")
    daemon = subprocess.Popen([args.tacse3d, "--board", board, "--calibration",
                               args.calibration, "--can-log", os.devnull, "--http",
                               f"127.0.0.1:{port}", "--seconds", "120"],
                              stdout=subprocess.DEVNULL, stderr=log)
    browser = None
    try:
        # The daemon's start under the sanitizers, beside another test on a loaded machine, once
        # took over 15 s: the bound only catches a daemon that never serves.
        wait_for("/api/state", lambda: get_json(base + "/api/state"), 60)

        browser = headless_chromium(1400)
        browser.get(base + "/")
        js = browser.execute_script

        wait_for("the stream", lambda: js("return document.getElementById('link').textContent")
                 == "live", 10)
        assert js("return document.getElementById('plots-missing').hidden"), \
            "the page says the plots are missing (uPlot not bundled)"
        assert js("return window.tacse3.plots()") == 6, "not every plot was created"
        assert js("return getComputedStyle(document.getElementById('recording')).display") == \
            "none", "the live page shows the recording's timeline"

        # The plots move: more samples, and the ω plot's pixels change.
        plot_png = "return document.querySelector('#plot-w canvas').toDataURL()"
        n0 = js("return window.tacse3.series.t.length")
        img0 = js(plot_png)
        time.sleep(2.0)
        n1 = js("return window.tacse3.series.t.length")
        assert n1 >= n0 + 20, f"the plots got {n1 - n0} samples in 2 s (20 Hz expected)"
        assert js(plot_png) != img0, "the angular-twist plot did not change in 2 s"

        # Both pads show an image, with the contact overlays on.
        for pad in ("left", "right"):
            sd = wait_for(f"the {pad} image", lambda: (lambda v: v if v > 5 else 0)(
                js(CANVAS_SD, pad)), 5)
            print(f"{pad} canvas: luma standard deviation {sd:.1f}")
        # The sim board renders both pads live; a loaded machine (the sanitizers) makes it drop
        # frames now and then, and the pad reads STALE for that moment. Wait for an OK reading.
        pad_left = "return document.querySelector('#pad-left .padstate').textContent"
        try:
            wait_for("the left pad to read OK", lambda: js(pad_left).startswith("OK"), 30)
        except AssertionError:
            raise AssertionError(f"left pad state reads {js(pad_left)!r} after 30 s")

        # The pose readout matches /api/state: wait for a moment when the page shows the cycle the
        # API serves (both change every 50 ms), then compare the angle shown with the API's.
        def same_cycle():
            cycle, shown, drawn = js("return [window.tacse3.last().cycle, "
                                     "document.getElementById('angle').textContent, "
                                     "window.tacse3.pose3d()]")
            api = get_json(base + "/api/state")
            return (shown, drawn, api) if api and api["cycle"] == cycle else None
        shown, drawn, api = wait_for("the page and /api/state on one cycle", same_cycle, 10)
        w = min(1.0, abs(api["pose"]["q"][0]))
        angle = 2 * math.degrees(math.acos(w))
        assert abs(float(shown) - angle) < 0.006, f"angle shown {shown}, /api/state {angle:.4f}"
        print(f"cycle {api['cycle']}: angle shown {shown} deg, /api/state {angle:.4f} deg")
        # The 3D view draws that pose: its end points are /api/state's quaternion and position.
        worst = check_pose3d(drawn, api["pose"]["q"], api["pose"]["p"])
        print(f"3D view: end points within {worst:.2g} px of /api/state's pose")
        assert js(CANVAS_HAS_RED), "the 3D view's canvas shows no red x axis"

        # Tare: the ACK on the page, and the pose restarts from identity (it has turned by then:
        # the scenario rotates 30 degrees about z).
        def angle_of(q):
            return 2 * math.degrees(math.acos(min(1.0, abs(q[0]))))
        page_pose = "return [window.tacse3.last().cycle, window.tacse3.last().pose.q]"
        assert js("return document.getElementById('controls-off').hidden"), "controls shown off"
        before = wait_for("the object to turn 8 degrees", lambda: (lambda cq: cq if angle_of(
            cq[1]) >= 8 else None)(js(page_pose)), 60)
        # The screenshot with the object turned, the 3D view showing it.
        browser.save_screenshot(args.screenshot)
        browser.find_element("id", "cmd-tare").click()
        ack = wait_for("the tare's answer on the page", lambda: (lambda t: t if "code" in t else
                       None)(js("return document.getElementById('ack').textContent")), 5)
        assert ack == "TARE: ACK (code 0, sequence 0)", f"the page shows {ack!r}"
        # The snapshot shown when the ACK came may predate the tare; the next one cannot (the DSP
        # thread applies a command before it answers).
        shown = js(page_pose)[0]
        after = wait_for("a cycle after the tare", lambda: (lambda cq: cq if cq[0] > shown
                         else None)(js(page_pose)), 5)
        a0, a1 = angle_of(before[1]), angle_of(after[1])
        assert a1 < a0 / 2, f"pose angle {a0:.2f} deg before the tare, {a1:.2f} deg after"
        print(f"tare: {ack!r}; pose angle {a0:.2f} deg at cycle {before[0]}, "
              f"{a1:.2f} deg at cycle {after[0]}")

        print(f"screenshot: {args.screenshot}")
        return 0
    except AssertionError:
        # What the daemon said (a sanitizer report, a refused port) explains most failures.
        log.flush()
        with open(args.screenshot + ".tacse3d.log") as f:
            print("tacse3d's log:\n" + f.read()[-4000:], file=sys.stderr)
        print(f"tacse3d exit status: {daemon.poll()}", file=sys.stderr)
        raise
    finally:
        if browser is not None:
            browser.quit()
        daemon.terminate()
        daemon.wait(timeout=20)
        log.close()


if __name__ == "__main__":
    sys.exit(main())
