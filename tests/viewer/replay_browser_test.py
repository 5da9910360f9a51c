#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tacse3-replay --view in headless Chromium (Debian's chromium, chromium-driver, python3-selenium).

Renders a short simulator recording with truth (tacse3-sim), serves it with tacse3-replay REC
--view 127.0.0.1:PORT and checks that: the page opens on frame 0; the scrubber moves the frame
shown (the cycle and time readouts, the pad image and the 3D view change, and the 3D view draws
that frame's pose and truth); play runs through the recording on its clock (never ahead of it,
not done sooner, stopping on the last frame) and pause stops it; the pose plot holds the truth series, equal at every frame to truth.csv's rotation vector.
Saves a screenshot to --screenshot. Exit 77 (ctest: skipped) when Chromium, its driver or
selenium is missing.
"""
import argparse
import csv
import json
import math
import os
import sys
import time
import urllib.request

from pose3d_check import check_pose3d
from viewer_support import (SKIP, chromium_missing, headless_chromium, served_recording,
                            wait_for)


def rotation_vector_deg(q):
    """The page's angle-axis: the short way round, angle times the unit axis, degrees."""
    w, x, y, z = q
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-12:
        return [0.0, 0.0, 0.0]
    angle = 2 * math.degrees(math.atan2(s, w))
    return [angle * x / s, angle * y / s, angle * z / s]


def check_scrub(js, base, frames, mid):
    """The scrubber to frame `mid`: the readouts, the image and the 3D view follow."""
    img0 = js("return document.querySelector('#pad-left canvas').toDataURL()")
    js("const f = document.getElementById('frame'); f.value = arguments[0];"
       "f.dispatchEvent(new Event('input'));", mid)
    wait_for(f"frame {mid} shown", lambda: js("return window.tacse3.recording().shown") == mid, 10)
    api = json.loads(urllib.request.urlopen(f"{base}/api/state?frame={mid}", timeout=5).read())
    cycle = js("return document.getElementById('cycle').textContent")
    t_shown = js("return document.getElementById('t').textContent")
    assert cycle == str(mid + 1), f"cycle readout {cycle!r} at frame {mid}"
    assert abs(float(t_shown) - api["t_us"] / 1e6) < 0.0006, f"time readout {t_shown} at {mid}"
    assert js("return document.getElementById('frame-index').textContent") == str(mid)
    img1 = js("return document.querySelector('#pad-left canvas').toDataURL()")
    assert img1 != img0, "the left pad's image did not change with the frame"
    drawn = js("return window.tacse3.pose3d()")
    worst = check_pose3d(drawn, api["pose"]["q"], api["pose"]["p"])
    assert "truth" in api, "a frame of a recording with truth.csv has no truth"
    assert not js("return document.getElementById('truth-caption').hidden")
    print(f"scrubber: frame {mid} of {frames}, cycle {cycle}, t {t_shown} s, image changed, "
          f"3D view within {worst:.2g} px of the frame's pose")


def check_play(js, browser, states):
    """Play from frame 0 to the end: never ahead of the recording's clock, not done before the
    recording's duration, through frames in between, stopping on the last; then pause holds. (How
    far play lags the clock is one frame's fetch, which depends on the machine's load: only
    bounded loosely.)"""
    js("const f = document.getElementById('frame'); f.value = 0;"
       "f.dispatchEvent(new Event('input'));")
    wait_for("frame 0 shown", lambda: js("return window.tacse3.recording().shown") == 0, 10)
    period_s = (states[1]["t_us"] - states[0]["t_us"]) / 1e6
    duration_s = (states[-1]["t_us"] - states[0]["t_us"]) / 1e6
    browser.find_element("id", "play").click()
    t0 = time.monotonic()
    seen, ahead = set(), 0.0
    while time.monotonic() - t0 < duration_s + 15:
        now = js("return window.tacse3.recording()")
        elapsed = time.monotonic() - t0
        seen.add(now["shown"])
        ahead = max(ahead, (states[now["index"]]["t_us"] - states[0]["t_us"]) / 1e6 - elapsed)
        if not now["playing"]:
            break
        time.sleep(0.05)
    elapsed = time.monotonic() - t0
    assert not now["playing"], f"still playing {elapsed:.1f} s into a {duration_s:.2f} s recording"
    assert now["shown"] == len(states) - 1, f"play stopped on frame {now['shown']}, not the last"
    assert ahead <= period_s + 0.05, f"play ran {ahead:.3f} s ahead of the recording's clock"
    assert elapsed >= duration_s - 0.05, f"played {duration_s:.2f} s in {elapsed:.2f} s"
    assert len(seen) >= 3, f"play showed only frames {sorted(seen)}"
    print(f"play: {duration_s:.3f} s of the recording in {elapsed:.3f} s, {len(seen)} frames "
          f"shown, never more than {max(ahead, 0.0) * 1e3:.0f} ms ahead of its clock")
    browser.find_element("id", "play").click()  # from the start again
    time.sleep(0.3)
    browser.find_element("id", "play").click()
    held = js("return window.tacse3.recording()")
    assert not held["playing"], "pause did not stop playing"
    time.sleep(0.3)
    assert js("return window.tacse3.recording().index") == held["index"], "frames moved on pause"
    print(f"pause: holds frame {held['index']}")


def check_truth_plot(js, rec_dir, states):
    """The pose plot's truth series at every frame is truth.csv's rotation vector there."""
    data = js("return window.tacse3.plotData(2)")
    assert len(data) == 7, f"the pose plot has {len(data) - 1} series, not 3 estimated + 3 truth"
    with open(os.path.join(rec_dir, "truth.csv")) as f:
        rows = list(csv.DictReader(f))  # tacse3-sim writes one row per frame, at its time
    assert len(rows) == len(states), f"truth.csv has {len(rows)} rows for {len(states)} frames"
    worst, peak = 0.0, 0.0
    for k, (s, row) in enumerate(zip(states, rows)):
        assert int(row["t_ns"]) // 1000 == s["t_us"], f"frame {k}: truth row at {row['t_ns']} ns"
        want = rotation_vector_deg([float(row[c]) for c in ("qw", "qx", "qy", "qz")])
        got = [data[4 + i][k] for i in range(3)]
        worst = max(worst, max(abs(a - b) for a, b in zip(got, want)))
        peak = max(peak, abs(want[2]))
    assert worst < 1e-4, f"the truth series differs from truth.csv by {worst:.3g} deg"
    assert peak > 5, f"the truth turns only {peak:.2f} deg about z: not the rendered motion"
    print(f"pose plot: truth series = truth.csv over {len(states)} frames (within {worst:.2g} "
          f"deg; peak {peak:.2f} deg about z)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sim", required=True)
    ap.add_argument("--replay", required=True)
    ap.add_argument("--screenshot", required=True)
    args = ap.parse_args()

    missing = chromium_missing()
    if missing:
        print(missing)
        return SKIP

    with served_recording(args.sim, args.replay, args.screenshot + ".replay.log",
                          "tacse3-replay-view-") as (rec, base, info):
        assert info["recording"] == rec, f"/api/info names {info['recording']}"
        frames = json.loads(urllib.request.urlopen(base + "/api/frames", timeout=5).read())
        states = frames["states"]
        assert frames["frames"] == len(states) == 180, f"{frames['frames']} frames served"

        browser = headless_chromium(1600)
        try:
            browser.get(base + "/")
            js = browser.execute_script
            wait_for("frame 0", lambda: js("return window.tacse3.recording().shown") == 0, 15)
            assert js("return document.getElementById('cycle').textContent") == "1"
            assert js("return document.getElementById('plots-missing').hidden"), "no uPlot bundled"
            check_scrub(js, base, len(states), 120)
            check_truth_plot(js, rec, states)
            check_play(js, browser, states)
            # The screenshot on the frame where the object has turned most.
            js("const f = document.getElementById('frame'); f.value = 150;"
               "f.dispatchEvent(new Event('input'));")
            wait_for("frame 150", lambda: js("return window.tacse3.recording().shown") == 150, 10)
            browser.save_screenshot(args.screenshot)
            print(f"screenshot: {args.screenshot}")
        finally:
            browser.quit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
