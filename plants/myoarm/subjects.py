"""The subjects of the MyoArm plant: one row per simulated person.

Sizes are scale factors of MyoArm's own segments (MoBL: Holzbaur et al.
2005, built on a 50th-percentile adult male), chosen from stature
percentiles (Pheasant & Haslegrave, Bodyspace, 3rd ed. 2006, British adults
19-65: men 1625 / 1740 / 1855 mm and women 1505 / 1610 / 1710 mm at the
5th / 50th / 95th percentile) with segment lengths proportional to stature
(Winter, Biomechanics and Motor Control of Human Movement, 4th ed. 2009,
after Drillis & Contini 1966: upper arm 0.186 H, forearm 0.146 H). So a
factor k = H / 1740 mm; the 5th-95th percentile range of either length is
k in [0.865, 1.066] (women's 5th to men's 95th). Two subjects vary the two
segments independently inside that range.

    k_upper  scales the humerus (GH centre -> elbow centre, l1)
    k_fore   scales ulna, radius and hand (elbow -> cuff, l2)
    passive  multiplies every muscle's passive force (calibration: README)
    forearm_mass  multiplies forearm and hand masses (a cast or splint)
    spastic  None, or the stretch reflex of README "Spasticity"
    role     "tuning" (kernel tuning may look at it) or "held-out" (never)

Masses scale with k^3 and inertias with k^5 (isotropic scaling of each
segment at constant density); muscle peak forces with k^2 (PCSA).
"""

# The stature ratios H / 1740 mm.
F05 = 1505 / 1740  # 0.865
F50 = 1610 / 1740  # 0.925
F95 = 1710 / 1740  # 0.983
M05 = 1625 / 1740  # 0.934
M50 = 1.0
M95 = 1855 / 1740  # 1.066

# Passive-muscle scale of the nominal (relaxed) subject: README "Passive forces".
PASSIVE = 0.25

# Stretch reflex (README "Spasticity"): thresholds in optimal fibre lengths
# per second, delay in s, gain in activation per (L0/s) above threshold,
# a_max the saturation of the reflex activation.
MODERATE = {"threshold": 0.04, "gain": 0.5, "delay": 0.040, "a_max": 0.06}
SEVERE = {"threshold": 0.02, "gain": 0.6, "delay": 0.040, "a_max": 0.10}

SUBJECTS = [
    {"name": "m50", "k_upper": M50, "k_fore": M50, "passive": PASSIVE, "forearm_mass": 1.0, "spastic": None,
     "role": "tuning", "note": "50th-percentile man (the model as published)"},
    {"name": "f05", "k_upper": F05, "k_fore": F05, "passive": PASSIVE, "forearm_mass": 1.0, "spastic": None,
     "role": "tuning", "note": "5th-percentile woman (smallest)"},
    {"name": "spastic_moderate", "k_upper": M50, "k_fore": M50, "passive": PASSIVE, "forearm_mass": 1.0,
     "spastic": MODERATE, "role": "tuning", "note": "50th-percentile man, moderate spasticity"},
    {"name": "m95", "k_upper": M95, "k_fore": M95, "passive": PASSIVE, "forearm_mass": 1.0, "spastic": None,
     "role": "held-out", "note": "95th-percentile man (largest)"},
    {"name": "f50", "k_upper": F50, "k_fore": F50, "passive": PASSIVE, "forearm_mass": 1.0, "spastic": None,
     "role": "held-out", "note": "50th-percentile woman"},
    {"name": "f95", "k_upper": F95, "k_fore": F95, "passive": PASSIVE, "forearm_mass": 1.0, "spastic": None,
     "role": "held-out", "note": "95th-percentile woman"},
    {"name": "m05", "k_upper": M05, "k_fore": M05, "passive": PASSIVE, "forearm_mass": 1.0, "spastic": None,
     "role": "held-out", "note": "5th-percentile man"},
    {"name": "long_forearm", "k_upper": 0.90, "k_fore": 1.05, "passive": PASSIVE, "forearm_mass": 1.0,
     "spastic": None, "role": "held-out", "note": "short upper arm, long forearm"},
    {"name": "long_upper", "k_upper": 1.05, "k_fore": 0.90, "passive": PASSIVE, "forearm_mass": 1.0,
     "spastic": None, "role": "held-out", "note": "long upper arm, short forearm"},
    {"name": "cast", "k_upper": M50, "k_fore": M50, "passive": PASSIVE, "forearm_mass": 1.5, "spastic": None,
     "role": "held-out", "note": "forearm and hand 50 % heavier (a cast): a real mass mismatch"},
    {"name": "stiff", "k_upper": F50, "k_fore": F50, "passive": 2 * PASSIVE, "forearm_mass": 1.0,
     "spastic": None, "role": "held-out", "note": "passive muscles twice as stiff (older adult)"},
    {"name": "spastic_severe", "k_upper": F50, "k_fore": F50, "passive": 1.5 * PASSIVE, "forearm_mass": 1.0,
     "spastic": SEVERE, "role": "held-out", "note": "50th-percentile woman, severe spasticity, stiffer passive"},
]

BY_NAME = {s["name"]: s for s in SUBJECTS}
