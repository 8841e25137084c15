#!/usr/bin/env python3
"""Measures the segments of a MyoArm subject as the diagnosis's person arm
reads them (`limb_sim::ArmParameters::person`, `spec/human-arm.md`).

    plants/myoarm/.venv/bin/python plants/myoarm/segments.py [NAME ...]   # default: m50

For each subject, at its settled rest posture, prints one JSON object per
segment: the upper arm (humerus, glenohumeral to elbow centre) and the
forearm with the hand (ulna, radius, carpals, fingers; elbow centre to the
cuff site), each with its length l [m], mass m [kg], centre of mass along
the segment as a fraction of l, and the divisor d of its inertia about the
centre of mass for rotation about the elbow's flexion axis, I_c = m l^2 / d.
The reference person of limb-sim (PERSON_UPPER_ARM, PERSON_FOREARM) is m50's.
"""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import plant as P  # noqa: E402


def segment(m, d, bodies, proximal, distal, axis):
    """Length, mass, centre fraction and inertia divisor of `bodies` spanning proximal -> distal."""
    length = float(np.linalg.norm(distal - proximal))
    mass = float(sum(m.body_mass[b] for b in bodies))
    centre = sum(m.body_mass[b] * d.xipos[b] for b in bodies) / mass
    inertia = 0.0
    for b in bodies:
        rot = d.ximat[b].reshape(3, 3)
        own = rot @ np.diag(m.body_inertia[b]) @ rot.T
        r = d.xipos[b] - centre
        r_perp = r - np.dot(r, axis) * axis
        inertia += axis @ own @ axis + m.body_mass[b] * np.dot(r_perp, r_perp)
    along = float(np.dot(centre - proximal, (distal - proximal) / length))
    return {"length_m": length, "mass_kg": mass, "centre": along / length,
            "inertia_divisor": mass * length * length / inertia}


def main(names):
    for name in names:
        plant = P.Plant(P.BY_NAME[name], seed=1, noise=False)
        m, d = plant.m, plant.d
        shoulder = d.xanchor[plant.j_sh]
        elbow = d.xanchor[plant.j_el]
        cuff = d.site_xpos[plant.site_cuff]
        axis = d.xaxis[plant.j_el]
        forearm = P.subtree(m, m.body(P.FOREARM_ROOT).id)
        print(json.dumps({
            "subject": name,
            "upper_arm": segment(m, d, [m.body("humerus_r").id], shoulder, elbow, axis),
            "forearm": segment(m, d, forearm, elbow, cuff, axis),
        }))


if __name__ == "__main__":
    main(sys.argv[1:] or ["m50"])
