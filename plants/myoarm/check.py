#!/usr/bin/env python3
"""Drives plant.py over limb-plant/1 with plant.md's estimation motion as an
open-loop impedance set-point (no kernel) and checks the plant.

    .venv/bin/python plants/myoarm/check.py [--subject NAME | --all] [--quick] [--noise on|off] [--rt-min R]

Session: 1 s hold at the start pose (set-point = the pose at t = 0), then the
minimum-jerk line from the grasp to x_R, z_R, psi_R (plant.md, l0 = 0.30 m,
qf = pi/4, v_max = 0.05 m/s: T = 27.15 s), then 2 s hold at x_R. --quick
stops after 3 s (CI). Prints one JSON object per subject and exits non-zero
when a check fails.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from subjects import SUBJECTS  # noqa: E402

L0, QF, VMAX = 0.30, math.pi / 4, 0.05
ELBOW_RANGE = (0.0, 2.269)
SHOULDER_ELV_RANGE = (0.0, 3.142)
LIMIT_TOL = 0.02  # rad: a soft joint limit may be entered this far


def motion(t, hold0=1.0):
    """plant.md's estimation set-point (pose, velocity, acceleration), after hold0 s of hold."""
    xr, zr, pr = L0 * (1 + math.cos(QF)), L0 * (1 + math.sin(QF)), math.pi / 2
    T = 1.875 * math.hypot(xr, zr) / VMAX
    tau = min(max((t - hold0) / T, 0.0), 1.0)
    s = 10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5
    sd = (30 * tau ** 2 - 60 * tau ** 3 + 30 * tau ** 4) / T if 0 < tau < 1 else 0.0
    sdd = (60 * tau - 180 * tau ** 2 + 120 * tau ** 3) / T ** 2 if 0 < tau < 1 else 0.0
    g = (xr, zr, pr)
    return [v * s for v in g], [v * sd for v in g], [v * sdd for v in g], T


def run(name, quick, noise, python, extra=(), rt_min=2.0):
    cmd = [python, os.path.join(HERE, "plant.py"), "--subject", name, "--noise", noise, *extra]
    p = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1)
    hs = json.loads(p.stdout.readline())
    assert hs["protocol"] == "limb-plant/1" and hs["dt"] == 0.001, hs
    p.stdin.write(json.dumps({"protocol": "limb-plant/1"}) + "\n")
    p.stdin.flush()
    _, _, _, T = motion(0)
    t_end = 3.0 if quick else 1.0 + T + 2.0
    r = {"subject": name}
    first = None
    weld = 0.0
    drift = 0.0
    fmax = fymax = tymax = ymax = 0.0
    ext = {}
    l1s, l2s = [], []
    wall0 = None
    last = None
    reflex = 0.0
    shift = 0.0
    while True:
        line = p.stdout.readline()
        if not line:
            break
        msg = json.loads(line)
        if "end" in msg:
            break
        f, tr = msg["frame"], msg["truth"]
        if first is None:
            first = (f, tr)
            wall0 = time.perf_counter()
        t = f["t"]
        weld = max(weld, tr["weld_error"])
        if t <= 1.0:
            drift = max(drift, math.hypot(f["x"] - first[0]["x"], f["z"] - first[0]["z"]))
        fmax = max(fmax, math.sqrt(f["fx"] ** 2 + f["fy"] ** 2 + f["fz"] ** 2))
        fymax = max(fymax, abs(f["fy"]))
        tymax = max(tymax, abs(f["ty"]))
        ymax = max(ymax, abs(f["y"]))
        reflex = max(reflex, tr["reflex_activation"])
        for k in ("elbow_flexion", "shoulder_elevation", "elv_angle", "shoulder_rot", "q1", "q2"):
            lo, hi = ext.get(k, (math.inf, -math.inf))
            ext[k] = (min(lo, tr[k]), max(hi, tr[k]))
        sh = (tr["shoulder_x"], tr["shoulder_y"], tr["shoulder_z"])
        if first is not None:
            s0 = (first[1]["shoulder_x"], first[1]["shoulder_y"], first[1]["shoulder_z"])
            shift = max(shift, math.dist(sh, s0))
        l1s.append(tr["l1"])
        l2s.append(tr["l2"])
        last = (f, tr)
        if t >= t_end - 1e-9:
            p.stdin.write(json.dumps({"end": "check done"}) + "\n")
            p.stdin.flush()
            break
        pos, vel, acc = motion(t)[:3]
        command = {"mode": "track", "xd": pos[0], "zd": pos[1], "psid": pos[2], "vxd": vel[0], "vzd": vel[1],
                   "vpsid": vel[2], "axd": acc[0], "azd": acc[1], "apsid": acc[2], "fx": 0.0, "fz": 0.0, "ty": 0.0}
        p.stdin.write(json.dumps({"command": command}) + "\n")
        p.stdin.flush()
    wall = time.perf_counter() - wall0
    rc = p.wait(timeout=30)
    f0, tr0 = first
    fl, trl = last
    r.update({
        "t_end": fl["t"],
        "weld_error_max_m": weld,
        "hold_drift_m": drift,
        "f_max_N": fmax, "fy_max_N": fymax, "ty_max_Nm": tymax,
        "lateral_y_max_m": ymax,
        "shoulder_rise_m": trl["shoulder_z"] - tr0["shoulder_z"],
        "shoulder_shift_max_m": shift,
        "l1_start_m": tr0["l1"], "l2_start_m": tr0["l2"],
        "l1_range_m": [min(l1s), max(l1s)], "l2_range_m": [min(l2s), max(l2s)],
        "start": {"q1": tr0["q1"], "q2": tr0["q2"], "elbow": [tr0["elbow_x"], tr0["elbow_y"], tr0["elbow_z"]],
                  "shoulder": [tr0["shoulder_x"], tr0["shoulder_y"], tr0["shoulder_z"]]},
        "end_pose": {"x": fl["x"], "z": fl["z"], "psi": fl["psi"], "fx": fl["fx"], "fz": fl["fz"], "ty": fl["ty"]},
        "joint_extremes": {k: list(v) for k, v in ext.items()},
        "reflex_activation_max": reflex,
        "rt_factor": fl["t"] / wall if wall > 0 else math.inf,
        "plant_exit": rc,
    })
    checks = {
        "weld_le_0.1mm": weld <= 1e-4,
        "table_carries_arm": drift <= 5e-4 and math.hypot(f0["fx"], f0["fz"]) < 2.0,
        "forces_plausible_lt_60N": fmax < 60.0,
        "joints_within_limits": (ext["elbow_flexion"][0] >= ELBOW_RANGE[0] - LIMIT_TOL
                                 and ext["elbow_flexion"][1] <= ELBOW_RANGE[1] + LIMIT_TOL
                                 and ext["shoulder_elevation"][0] >= SHOULDER_ELV_RANGE[0] - LIMIT_TOL
                                 and ext["shoulder_elevation"][1] <= SHOULDER_ELV_RANGE[1] + LIMIT_TOL),
        "rt_factor_ge_min": r["rt_factor"] >= rt_min,
        "plant_exit_0": rc == 0,
    }
    r["checks"] = checks
    r["pass"] = all(checks.values())
    return r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--subject", default="m50")
    ap.add_argument("--all", action="store_true")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--noise", choices=["on", "off"], default="off")
    ap.add_argument("--python", default=sys.executable)
    ap.add_argument("--passive", type=float, help="passed to plant.py (calibration runs)")
    ap.add_argument("--rt-min", type=float, default=2.0,
                    help="real-time factor the check requires (a machine busy with other work may need less)")
    args = ap.parse_args()
    names = [s["name"] for s in SUBJECTS] if args.all else [args.subject]
    ok = True
    for n in names:
        extra = ["--passive", str(args.passive)] if args.passive is not None else []
        r = run(n, args.quick, args.noise, args.python, extra, args.rt_min)
        print(json.dumps(r), flush=True)
        ok = ok and r["pass"]
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
