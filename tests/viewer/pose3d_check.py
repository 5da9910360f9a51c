# SPDX-License-Identifier: Apache-2.0
"""Checks the page's 3D pose view against a pose: the end points the page drew (window.tacse3.
pose3d()) recomputed here from the quaternion with a rotation matrix (the page rotates with the
quaternion's vector form), projected on the view basis the page reports."""


def rotation_matrix(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def expected_ends(drawn, q, p):
    """G's and the object's origin and axis tips in canvas pixels, for pose (q, p) in (1, m)."""
    right, up = drawn["basis"]["right"], drawn["basis"]["up"]
    k, L = drawn["px_per_mm"], drawn["axis_mm"]

    def at(g):
        return [drawn["cx"] + k * sum(r * c for r, c in zip(right, g)),
                drawn["cy"] - k * sum(u * c for u, c in zip(up, g))]
    R = rotation_matrix(q)
    o = [c * 1e3 * drawn["p_scale"] for c in p]
    axes = [[L if i == j else 0 for i in range(3)] for j in range(3)]
    moved = [[sum(R[r][c] * v[c] for c in range(3)) + o[r] for r in range(3)] for v in axes]
    return {"g": {"origin": at([0, 0, 0]), "axes": [at(v) for v in axes]},
            "object": {"origin": at(o), "axes": [at(v) for v in moved]}}


def check_pose3d(drawn, q, p, tol_px=1e-6):
    """Raises AssertionError when the drawing does not show pose (q, p); returns the largest
    difference in pixels."""
    want = expected_ends(drawn, q, p)
    worst = 0.0
    for frame in ("g", "object"):
        pts_got = [drawn[frame]["origin"]] + drawn[frame]["axes"]
        pts_want = [want[frame]["origin"]] + want[frame]["axes"]
        for got, exp in zip(pts_got, pts_want):
            worst = max(worst, abs(got[0] - exp[0]), abs(got[1] - exp[1]))
    assert worst <= tol_px, f"3D view: an end point is {worst:.3g} px from the pose's"
    # The view basis is orthonormal (else the projection distorts lengths).
    right, up = drawn["basis"]["right"], drawn["basis"]["up"]
    dots = [sum(a * b for a, b in zip(u, v)) for u, v in ((right, right), (up, up), (right, up))]
    assert abs(dots[0] - 1) < 1e-9 and abs(dots[1] - 1) < 1e-9 and abs(dots[2]) < 1e-9, \
        f"3D view: the view basis is not orthonormal ({dots})"
    return worst
