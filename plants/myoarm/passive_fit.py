#!/usr/bin/env python3
"""Fits the passive muscle torques a MyoArm session logged as a linear
function of the plant's joint angles, to show their form.

    plants/myoarm/.venv/bin/python plants/myoarm/passive_fit.py LOG.csv [...]

LOG.csv is a `limb run --plant myoarm --log` (or `limb population --plant
myoarm --log-dir`) log: its truth columns `passive_torque_shoulder` and
`passive_torque_elbow` [N m] are the muscles' passive generalised forces at
shoulder elevation and elbow flexion, q1 and q2 [rad] plant.md's angles.
Over the lift (t > 6 s) each torque is fitted as a + b q1 + c q2 by least
squares; prints the coefficients, the fit's RMS residual and the torque's
standard deviation [N m], one line per log and joint.
"""
import sys

import numpy as np


def main(paths):
    for path in paths:
        d = np.genfromtxt(path, delimiter=",", names=True)
        lift = d["t"] > 6.0
        a = np.c_[np.ones(lift.sum()), d["q1"][lift], d["q2"][lift]]
        for joint in ("shoulder", "elbow"):
            tau = d["passive_torque_" + joint][lift]
            coef = np.linalg.lstsq(a, tau, rcond=None)[0]
            rms = float(np.sqrt(np.mean((a @ coef - tau) ** 2)))
            print("%s %s: %.2f %+.2f q1 %+.2f q2  rms %.3f  sd %.3f  (q1 %.2f..%.2f, q2 %.2f..%.2f)" % (
                path, joint, coef[0], coef[1], coef[2], rms, float(tau.std()),
                d["q1"][lift].min(), d["q1"][lift].max(), d["q2"][lift].min(), d["q2"][lift].max()))


if __name__ == "__main__":
    main(sys.argv[1:])
