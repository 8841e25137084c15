#!/usr/bin/env python3
"""MyoArm plant: MuJoCo + MyoSuite's myoarm_r speaking limb-plant/1.

    plant.py --subject NAME [--seed N] [--noise on|off] [--tcp PORT] [--duration S]
    plant.py --list-subjects

A passive musculoskeletal right arm (MoBL via myo_sim, thorax fixed, shoulder
girdle coupled to shoulder elevation) lies reclined on a table; plant.md's
Cartesian impedance robot grasps it at a cuff on the distal radius (weld,
site to site). The protocol is ../../../shared/spec/external-plant.md; the
posture, frame S, robot, table, subjects and checks are in README.md.
stdout carries only protocol lines; diagnostics go to stderr.
"""
import argparse
import json
import math
import os
import socket
import sys
import warnings

import numpy as np

warnings.filterwarnings("ignore")  # myo_sim's "empty prefix" warning

import mujoco  # noqa: E402
import myo_sim  # noqa: E402

# MuJoCo's own warning handler prints to stdout and writes MUJOCO_LOG.TXT: send warnings to stderr.
mujoco.set_mju_user_warning(lambda msg: print(f"mujoco warning: {msg}", file=sys.stderr, flush=True))

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from subjects import BY_NAME, SUBJECTS  # noqa: E402

DT = 0.001  # frame period [s]
SUBSTEPS = int(os.environ.get("MYOARM_SUBSTEPS", "1"))  # MuJoCo steps per frame (1: 1 ms)
G = 9.81

# plant.md's impedance (x, z, psi).
LAM = np.array([2.0, 2.0, 0.05])
K = np.array([200.0, 200.0, 10.0])
D = 2.0 * 2.0 * np.sqrt(K * LAM)
# Out-of-plane holding of the cuff: lateral y, roll about S x, yaw about S z.
K_Y, K_ROLL, K_YAW = 3000.0, 30.0, 30.0
I_ROT = 0.05
D_Y = 2.0 * 2.0 * math.sqrt(K_Y * 2.0)
D_ROLL = 2.0 * 2.0 * math.sqrt(K_ROLL * I_ROT)
D_YAW = D_ROLL

NOISE_POS, NOISE_PSI, NOISE_F, NOISE_T = 1e-4, 1e-3, 0.5, 0.025

# Muscles kept: everything crossing the shoulder or the elbow that does not
# also cross the wrist or the fingers (those joints are removed).
KEEP_MUSCLES = ["DELT1", "DELT2", "DELT3", "SUPSP", "INFSP", "SUBSC", "TMIN", "TMAJ", "PECM1", "PECM2", "PECM3",
                "LAT1", "LAT2", "LAT3", "CORB", "TRIlong", "TRIlat", "TRImed", "ANC", "BIClong", "BICshort", "BRA",
                "BRD", "PT"]
ARM_JOINTS = ["elv_angle_r", "shoulder_elv_r", "shoulder1_r2_r", "shoulder_rot_r", "elbow_flexion_r"]
GIRDLE_PREFIX = ("sternoclav", "unrotscap", "acromioclav", "unrothum")
# Muscles that receive the spastic stretch reflex: shoulder flexors/extensors
# and elbow flexors/extensors.
SPASTIC_MUSCLES = ["DELT1", "PECM1", "CORB", "DELT3", "LAT1", "TMAJ", "TRIlong", "TRIlat", "TRImed", "BIClong",
                   "BICshort", "BRA", "BRD"]
CONTACT_GEOMS = ["humerus_coll_r", "ulna_coll_r", "radius_coll_r", "radius_coll_2_r", "radius_coll_3_r",
                 "3mcskin_coll_r"]
FOREARM_ROOT = "ulna_r"

# Rest posture (before settling): plane of elevation sagittal (flexion),
# a little shoulder flexion and elbow flexion, forearm neutral (pro_sup 0).
REST = {"elv_angle_r": math.pi / 2, "shoulder_elv_r": 0.20, "shoulder_rot_r": 0.0, "elbow_flexion_r": 0.15}
CUFF_FRACTION = 0.85  # cuff on the radius, this fraction of the way radius origin -> wrist (lunate)
SETTLE_S = 2.0

TRUTH = ["q1", "q2", "elbow_x", "elbow_y", "elbow_z", "shoulder_x", "shoulder_y", "shoulder_z",
         "cuff_x", "cuff_y", "cuff_z", "l1", "l2", "elbow_flexion", "shoulder_elevation", "elv_angle",
         "shoulder_rot", "forearm_psi", "weld_error", "passive_torque_shoulder", "passive_torque_elbow",
         "reflex_activation"]


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def quat_from_matrix(r):
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(r).reshape(9))
    return q


def apply_couplings(m, qpos):
    """Sets the girdle joints from shoulder elevation by the model's joint equalities."""
    for i in range(m.neq):
        if m.eq_type[i] != mujoco.mjtEq.mjEQ_JOINT:
            continue
        j1, j2 = m.eq_obj1id[i], m.eq_obj2id[i]
        c = m.eq_data[i][:5]
        x = qpos[m.jnt_qposadr[j2]]
        qpos[m.jnt_qposadr[j1]] = c[0] + c[1] * x + c[2] * x * x + c[3] * x ** 3 + c[4] * x ** 4


def arm_spec():
    """myoarm_r with only the shoulder and elbow: wrist, fingers and pro_sup removed (rigid forearm, neutral)."""
    s = myo_sim.load_spec("myoarm_r")
    keep_tendons = set()
    for a in list(s.actuators):
        if a.name in KEEP_MUSCLES:
            keep_tendons.add(a.target)
        else:
            s.delete(a)
    for t in list(s.tendons):
        if t.name not in keep_tendons:
            s.delete(t)
    for j in list(s.joints):
        if j.name in ARM_JOINTS or j.name.startswith(GIRDLE_PREFIX):
            continue
        s.delete(j)
    # Speed: keep only the sites and wrapping geoms of the kept muscle paths and
    # the contact geoms; the bodies keep their compiled mass and inertia.
    m = s.compile()
    used_sites, used_geoms = set(), set(CONTACT_GEOMS)
    for w in range(m.nwrap):
        t, o = int(m.wrap_type[w]), int(m.wrap_objid[w])
        if t == int(mujoco.mjtWrap.mjWRAP_SITE):
            used_sites.add(m.site(o).name)
        elif t in (int(mujoco.mjtWrap.mjWRAP_SPHERE), int(mujoco.mjtWrap.mjWRAP_CYLINDER)):
            used_geoms.add(m.geom(o).name)
            if int(m.wrap_prm[w]) >= 0:
                used_sites.add(m.site(int(m.wrap_prm[w])).name)
    for p in list(s.pairs):
        s.delete(p)
    for b in s.bodies:
        if b.name == "world":
            continue
        mb = m.body(b.name)
        b.explicitinertial = True
        b.mass = float(mb.mass[0])
        b.ipos = mb.ipos.copy()
        b.iquat = mb.iquat.copy()
        b.inertia = mb.inertia.copy()
        b.fullinertia = [np.nan, 0, 0, 0, 0, 0]
    for st in list(s.sites):
        if st.name not in used_sites:
            s.delete(st)
    for g in list(s.geoms):
        if g.name not in used_geoms:
            s.delete(g)
    return s


def subtree(m, root):
    ids = [root]
    for b in range(m.nbody):
        p = b
        while p != 0 and p != root:
            p = m.body_parentid[p]
        if p == root and b != root:
            ids.append(b)
    return ids


def scale_segment(m, body_ids, k, mass_factor):
    """Isotropic scaling of the bodies' own frames' contents by k; mass k^3 (times mass_factor), inertia k^5."""
    bset = set(body_ids)
    for b in body_ids:
        m.body_ipos[b] *= k
        m.body_mass[b] *= k ** 3 * mass_factor
        m.body_inertia[b] *= k ** 5 * mass_factor
    for b in range(m.nbody):
        if m.body_parentid[b] in bset and b != m.body_parentid[b]:
            m.body_pos[b] *= k
    for i in range(m.nsite):
        if m.site_bodyid[i] in bset:
            m.site_pos[i] *= k
            m.site_size[i] *= k
    for i in range(m.ngeom):
        if m.geom_bodyid[i] in bset:
            m.geom_pos[i] *= k
            if m.geom_type[i] != mujoco.mjtGeom.mjGEOM_MESH:
                m.geom_size[i] *= k
            m.geom_rbound[i] *= k
    for j in range(m.njnt):
        if m.jnt_bodyid[j] in bset:
            m.jnt_pos[j] *= k


class Plant:
    def __init__(self, subject, seed=1, noise=True):
        self.subject = subject
        self.rng = np.random.default_rng(seed)
        self.noise = noise
        self._build()
        self._settle()

    # ---------------------------------------------------------------- model
    def _build(self):
        sub = self.subject
        # 1. the arm alone, scaled, to find the rest posture, frame S and the cuff
        spec = arm_spec()
        m0 = spec.compile()
        self._scale(m0, None)
        d0 = mujoco.MjData(m0)
        q = d0.qpos
        q[:] = 0
        for n, v in REST.items():
            q[m0.joint(n).qposadr[0]] = v
        apply_couplings(m0, q)
        mujoco.mj_kinematics(m0, d0)
        elbow = d0.xanchor[m0.joint("elbow_flexion_r").id].copy()
        rad = m0.body("radius_r").id
        lun = m0.body("lunate_r").id
        cuff = d0.xpos[rad] + CUFF_FRACTION * (d0.xpos[lun] - d0.xpos[rad])
        f = cuff - elbow
        # Model frame: +z superior, -y anterior, -x lateral (right arm). The
        # person reclines about the lateral axis by alpha so that the forearm
        # (elbow -> cuff) is horizontal in the sagittal plane.
        alpha = math.atan2(-f[1], -f[2])
        up = np.array([0.0, -math.cos(alpha), math.sin(alpha)])
        sup = np.array([0.0, 0.0, 1.0])
        xs = sup - sup.dot(up) * up
        xs /= np.linalg.norm(xs)
        ys = np.cross(up, xs)
        R = np.column_stack([xs, ys, up])  # S axes in model coordinates
        self.alpha = alpha
        # cuff site in the radius frame, oriented as S at the rest posture
        rr = d0.xmat[rad].reshape(3, 3)
        cuff_local = rr.T @ (cuff - d0.xpos[rad])
        cuff_quat = quat_from_matrix(rr.T @ R)
        # table top: the lowest point of the forearm contact geoms at rest
        low = []
        for gname in CONTACT_GEOMS:
            g = m0.geom(gname).id
            gm = d0.geom_xmat[g].reshape(3, 3)
            r, h = m0.geom_size[g][0], m0.geom_size[g][1]
            ax = gm[:, 2]
            c = d0.geom_xpos[g]
            lowest = min((c + h * ax).dot(up), (c - h * ax).dot(up)) - r
            low.append((gname, lowest))
        forearm_low = min(v for n, v in low if n != "humerus_coll_r")
        table_top = forearm_low + 0.002  # starts 2 mm into the pad: it carries the arm from the first step

        # 2. the full model: arm + cuff site + robot + table
        spec = arm_spec()
        spec.option.gravity = -G * up
        spec.option.timestep = DT / SUBSTEPS
        spec.body("radius_r").add_site(name="cuff", pos=cuff_local / sub["k_fore"], quat=cuff_quat, size=[0.01, 0, 0])
        rob = spec.worldbody.add_body(name="robot", pos=cuff, quat=quat_from_matrix(R), gravcomp=1.0)
        rob.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.02, 0, 0], contype=0, conaffinity=0, density=0.0)
        rob.explicitinertial = True
        rob.mass = 2.0
        rob.ipos = [0, 0, 0]
        rob.inertia = [I_ROT, I_ROT, I_ROT]
        for name, typ, axis in [("rob_x", mujoco.mjtJoint.mjJNT_SLIDE, [1, 0, 0]),
                                ("rob_y", mujoco.mjtJoint.mjJNT_SLIDE, [0, 1, 0]),
                                ("rob_z", mujoco.mjtJoint.mjJNT_SLIDE, [0, 0, 1]),
                                ("rob_pitch", mujoco.mjtJoint.mjJNT_HINGE, [0, 1, 0]),
                                ("rob_roll", mujoco.mjtJoint.mjJNT_HINGE, [1, 0, 0]),
                                ("rob_yaw", mujoco.mjtJoint.mjJNT_HINGE, [0, 0, 1])]:
            rob.add_joint(name=name, type=typ, axis=axis, damping=0.0, armature=0.0)
        rob.add_site(name="robot_site", pos=[0, 0, 0])
        spec.add_equality(type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_SITE, name1="robot_site",
                          name2="cuff", solref=[0.005, 1.0])
        # table: a padded box, its top plane at table_top, normal = up
        centre = 0.5 * (elbow + cuff)
        centre = centre - (centre.dot(up) - (table_top - 0.05)) * up
        spec.worldbody.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.45, 0.25, 0.05],
                                pos=centre, quat=quat_from_matrix(R), contype=0, conaffinity=2,
                                friction=[0.6, 0.005, 0.0001], solref=[0.01, 1.0], solimp=[0.9, 0.95, 0.002, 0.5, 2])
        m = spec.compile()
        for g in range(m.ngeom):
            name = m.geom(g).name
            if name in CONTACT_GEOMS:
                m.geom_contype[g], m.geom_conaffinity[g] = 2, 0
            elif name == "table":
                m.geom_contype[g], m.geom_conaffinity[g] = 0, 2
            else:
                m.geom_contype[g], m.geom_conaffinity[g] = 0, 0
        self._scale(m, self.subject)
        self.m = m
        self.d = mujoco.MjData(m)
        self.R = R
        self.up = up
        self.table_top = table_top
        # indices
        jid = lambda n: m.joint(n).id  # noqa: E731
        self.rob_dof = np.array([m.jnt_dofadr[jid(n)] for n in
                                 ["rob_x", "rob_y", "rob_z", "rob_pitch", "rob_roll", "rob_yaw"]])
        self.rob_qpos = np.array([m.jnt_qposadr[jid(n)] for n in
                                  ["rob_x", "rob_y", "rob_z", "rob_pitch", "rob_roll", "rob_yaw"]])
        self.rob_q0, self.rob_v0 = int(self.rob_qpos[0]), int(self.rob_dof[0])
        assert (np.diff(self.rob_qpos) == 1).all() and (np.diff(self.rob_dof) == 1).all()
        self.j_sh = jid("shoulder_elv_r")
        self.j_el = jid("elbow_flexion_r")
        self.qa = {n: m.jnt_qposadr[jid(n)] for n in ARM_JOINTS}
        self.dof_sh = m.jnt_dofadr[self.j_sh]
        self.dof_el = m.jnt_dofadr[self.j_el]
        self.site_cuff = m.site("cuff").id
        self.site_rob = m.site("robot_site").id
        q = self.d.qpos
        q[:] = 0
        for n, v in REST.items():
            q[self.qa[n]] = v
        apply_couplings(m, q)
        mujoco.mj_forward(m, self.d)
        # spastic reflex
        sp = sub["spastic"]
        self.spastic = sp
        if sp:
            self.sp_ids = np.array([m.actuator(n).id for n in SPASTIC_MUSCLES])
            lr = m.actuator_lengthrange[self.sp_ids]
            rng = m.actuator_gainprm[self.sp_ids, :2]
            self.sp_l0 = (lr[:, 1] - lr[:, 0]) / (rng[:, 1] - rng[:, 0])
            self.sp_delay = max(1, int(round(sp["delay"] / DT)))
            self.sp_buf = np.zeros((self.sp_delay, len(self.sp_ids)))
            self.sp_k = 0
        self.reflex = 0.0

    def _scale(self, m, _):
        """Subject scaling of a compiled model (sizes, masses, muscle forces and passive scale)."""
        sub = self.subject
        ku, kf = sub["k_upper"], sub["k_fore"]
        # reference muscle lengths before scaling (at the rest posture)
        d = mujoco.MjData(m)
        for n, v in REST.items():
            d.qpos[m.joint(n).qposadr[0]] = v
        apply_couplings(m, d.qpos)
        mujoco.mj_forward(m, d)
        len0 = d.actuator_length.copy()
        scale_segment(m, [m.body("humerus_r").id], ku, 1.0)
        fore = subtree(m, m.body(FOREARM_ROOT).id)
        scale_segment(m, fore, kf, sub["forearm_mass"])
        mujoco.mj_setConst(m, d)
        mujoco.mj_forward(m, d)
        ratio = d.actuator_length / len0
        for a in range(m.nu):
            m.actuator_lengthrange[a] *= ratio[a]
            # peak isometric force ~ PCSA ~ k^2 (the segments the muscle spans)
            k2 = (kf if m.actuator(a).name in ("BRA", "BRD", "PT", "ANC") else ku) ** 2
            m.actuator_gainprm[a][2] *= k2
            m.actuator_biasprm[a][2] *= k2
            m.actuator_biasprm[a][7] *= sub["passive"]
        mujoco.mj_setConst(m, d)

    # ---------------------------------------------------------------- state
    def _robot_pose(self):
        q = self.d.qpos[self.rob_qpos]
        return q  # x, y, z, pitch, roll, yaw relative to the robot's build pose (S axes)

    def _settle(self):
        """Lets the arm come to rest on the table: the robot limp in x, z, psi (own weight compensated),
        holding y, roll and yaw; then frame S starts at the settled grasp."""
        m, d = self.m, self.d
        self.sp_y = np.zeros(3)  # y, roll, yaw set-points (robot coordinates)
        n = int(SETTLE_S / m.opt.timestep)
        extra = np.zeros(m.nv)
        for i in range(n):
            # extra damping on the arm while settling, fading out
            fade = max(0.0, 1.0 - i / (0.7 * n))
            extra[:] = 0
            d.qfrc_applied[:] = -2.0 * fade * d.qvel
            # the robot only damps: its set-points follow the pose (limp, own weight compensated)
            d.qfrc_applied[self.rob_dof[[0, 2, 3]]] = -D * d.qvel[self.rob_dof[[0, 2, 3]]]
            d.qfrc_applied[self.rob_dof[[1, 4, 5]]] = -np.array([D_Y, D_ROLL, D_YAW]) * d.qvel[self.rob_dof[[1, 4, 5]]]
            mujoco.mj_step(m, d)
        d.qfrc_applied[:] = 0
        q = d.qpos[self.rob_qpos]
        self.sp_y = np.array([q[1], q[4], q[5]])
        self.origin = self._robot_pose().copy()
        self.sp = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # in S: x z psi, rates, accels
        self.impedance = True
        self.wrench = np.zeros(3)
        self.held = None
        self.t = 0.0
        self.f_ext = np.zeros(4)  # fx, fy, fz, ty
        self.weld_max = 0.0
        c = d.site_xpos[self.site_cuff]
        self.origin_world = c.copy()
        self.f_ext = d.qfrc_constraint[self.rob_dof][:4].copy()
        vel = np.abs(d.qvel).max()
        log(f"myoarm: settled after {SETTLE_S} s, max |qvel| {vel:.2e}, "
            f"elbow_flexion {d.qpos[self.qa['elbow_flexion_r']]:.3f}, "
            f"shoulder_elv {d.qpos[self.qa['shoulder_elv_r']]:.3f}, ncon {d.ncon}")

    def _out_of_plane(self):
        d = self.d
        q = d.qpos[self.rob_qpos]
        v = d.qvel[self.rob_dof]
        f = d.qfrc_applied
        f[self.rob_dof[1]] = K_Y * (self.sp_y[0] - q[1]) - D_Y * v[1]
        f[self.rob_dof[4]] = K_ROLL * (self.sp_y[1] - q[4]) - D_ROLL * v[4]
        f[self.rob_dof[5]] = K_YAW * (self.sp_y[2] - q[5]) - D_YAW * v[5]

    def pose_s(self):
        """Robot pose in S: x, y, z, psi."""
        q = self._robot_pose()
        o = self.origin
        return np.array([q[0] - o[0], q[1] - o[1], q[2] - o[2], q[3] - o[3]])

    def vel_s(self):
        v = self.d.qvel[self.rob_dof]
        return np.array([v[0], v[2], v[3]])

    def to_s(self, p):
        return self.R.T @ (p - self.origin_world)

    def truth(self):
        m, d = self.m, self.d
        gh = self.to_s(d.xanchor[self.j_sh])
        el = self.to_s(d.xanchor[self.j_el])
        cu = self.to_s(d.site_xpos[self.site_cuff])
        q1 = math.atan2(el[2] - gh[2], gh[0] - el[0])
        psi = math.atan2(cu[2] - el[2], el[0] - cu[0])
        werr = float(np.linalg.norm(d.site_xpos[self.site_cuff] - d.site_xpos[self.site_rob]))
        self.weld_max = max(self.weld_max, werr)
        # passive (muscle) generalised forces at shoulder elevation and elbow flexion
        pt_sh = float(d.qfrc_actuator[self.dof_sh]) if not self.spastic else float(self._passive_dof(self.dof_sh))
        pt_el = float(d.qfrc_actuator[self.dof_el]) if not self.spastic else float(self._passive_dof(self.dof_el))
        return {"q1": q1, "q2": psi - q1,
                "elbow_x": el[0], "elbow_y": el[1], "elbow_z": el[2],
                "shoulder_x": gh[0], "shoulder_y": gh[1], "shoulder_z": gh[2],
                "cuff_x": cu[0], "cuff_y": cu[1], "cuff_z": cu[2],
                "l1": float(np.linalg.norm(el - gh)), "l2": float(np.linalg.norm(cu - el)),
                "elbow_flexion": float(d.qpos[self.qa["elbow_flexion_r"]]),
                "shoulder_elevation": float(d.qpos[self.qa["shoulder_elv_r"]]),
                "elv_angle": float(d.qpos[self.qa["elv_angle_r"]]),
                "shoulder_rot": float(d.qpos[self.qa["shoulder_rot_r"]]),
                "forearm_psi": psi, "weld_error": werr,
                "passive_torque_shoulder": pt_sh, "passive_torque_elbow": pt_el,
                "reflex_activation": float(self.reflex)}

    def _passive_dof(self, dof):
        """Generalised force of the muscles' passive (bias) part alone at one dof."""
        m, d = self.m, self.d
        f = np.zeros(m.nu)
        for a in range(m.nu):
            f[a] = mujoco.mju_muscleBias(d.actuator_length[a], m.actuator_lengthrange[a], m.actuator_acc0[a],
                                         m.actuator_biasprm[a][:9])
        mom = np.zeros((m.nu, m.nv))
        mujoco.mju_sparse2dense(mom, d.actuator_moment, d.moment_rownnz, d.moment_rowadr, d.moment_colind)
        return mom[:, dof] @ f

    # ---------------------------------------------------------------- stepping
    def command(self, cmd):
        mode = cmd.get("mode")
        if mode not in ("track", "hold", "stop"):
            raise ValueError(f"unknown mode {mode!r}")
        keys = ("xd", "zd", "psid")
        have = [k in cmd for k in keys]
        if any(have) and not all(have):
            raise ValueError("xd, zd, psid must come together")
        num = lambda k: self._num(cmd, k)  # noqa: E731
        self.wrench = np.array([num("fx"), num("fz"), num("ty")])
        if all(have):
            self.sp = np.array([num(k) for k in ("xd", "zd", "psid", "vxd", "vzd", "vpsid", "axd", "azd", "apsid")])
            self.impedance = True
            self.held = None
        elif mode == "hold":
            if self.held is None:
                p = self.pose_s()
                self.held = np.array([p[0], p[2], p[3]])
            self.sp = np.concatenate([self.held, np.zeros(6)])
            self.impedance = True
        elif mode == "stop":
            self.impedance = False
            self.held = None
        else:
            raise ValueError("track without a set-point")

    @staticmethod
    def _num(cmd, k):
        v = cmd.get(k, 0.0)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ValueError(f"{k} is not a finite number")
        return float(v)

    def _reflex(self):
        if not self.spastic:
            return
        m, d, sp = self.m, self.d, self.spastic
        v = d.actuator_velocity[self.sp_ids] / self.sp_l0  # lengthening > 0, in L0/s
        delayed = self.sp_buf[self.sp_k].copy()
        self.sp_buf[self.sp_k] = v
        self.sp_k = (self.sp_k + 1) % self.sp_delay
        a = np.clip(sp["gain"] * (delayed - sp["threshold"]), 0.0, sp["a_max"])
        d.ctrl[self.sp_ids] = a
        self.reflex = float(a.max())

    def step(self):
        m, d = self.m, self.d
        self._reflex()
        qa, va = self.rob_q0, self.rob_v0
        qpos, qvel, fa = d.qpos, d.qvel, d.qfrc_applied
        o = self.origin
        sp = self.sp
        imp = self.impedance
        k0, k1, k2 = K
        d0, d1, d2 = D
        l0, l1, l2 = LAM
        spy, spr, spw = self.sp_y
        for _ in range(SUBSTEPS):
            if imp:
                fx = k0 * (sp[0] - (qpos[qa] - o[0])) + d0 * (sp[3] - qvel[va]) + l0 * sp[6]
                fz = k1 * (sp[1] - (qpos[qa + 2] - o[2])) + d1 * (sp[4] - qvel[va + 2]) + l1 * sp[7]
                tp = k2 * (sp[2] - (qpos[qa + 3] - o[3])) + d2 * (sp[5] - qvel[va + 3]) + l2 * sp[8]
            else:
                fx, fz, tp = self.wrench
            fa[va] = fx
            fa[va + 2] = fz
            fa[va + 3] = tp
            fa[va + 1] = K_Y * (spy - qpos[qa + 1]) - D_Y * qvel[va + 1]
            fa[va + 4] = K_ROLL * (spr - qpos[qa + 4]) - D_ROLL * qvel[va + 4]
            fa[va + 5] = K_YAW * (spw - qpos[qa + 5]) - D_YAW * qvel[va + 5]
            mujoco.mj_step(m, d)
        # the arm's wrench on the robot through the weld: f_ext = -F (F: the robot's wrench on the arm)
        self.f_ext = d.qfrc_constraint[va:va + 4].copy()
        self.t = round(self.t + DT, 9)

    def frame(self):
        p = self.pose_s()
        f = self.f_ext
        if self.noise:
            n = self.rng.normal
            p = p + np.array([n(0, NOISE_POS), n(0, NOISE_POS), n(0, NOISE_POS), n(0, NOISE_PSI)])
            f = f + np.array([n(0, NOISE_F), n(0, NOISE_F), n(0, NOISE_F), n(0, NOISE_T)])
        return {"t": self.t, "x": float(p[0]), "y": float(p[1]), "z": float(p[2]), "psi": float(p[3]),
                "fx": float(f[0]), "fy": float(f[1]), "fz": float(f[2]), "ty": float(f[3])}


class Stream:
    def __init__(self, tcp, out=None):
        if tcp is None:
            self.inp, self.out = sys.stdin, out or sys.stdout
        else:
            server = socket.socket()
            server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            server.bind(("127.0.0.1", tcp))
            server.listen(1)
            log(f"listening on {server.getsockname()[1]}")
            conn, _ = server.accept()
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.inp = conn.makefile("r", encoding="utf-8")
            self.out = conn.makefile("w", encoding="utf-8")

    def send(self, obj):
        self.out.write(json.dumps(obj, allow_nan=False, separators=(",", ":")) + "\n")
        self.out.flush()

    def receive(self):
        return self.inp.readline()


def _reject_constant(c):
    raise ValueError(f"{c} is not a JSON number")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--subject", default="m50")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--noise", choices=["on", "off"], default="on")
    p.add_argument("--tcp", type=int)
    p.add_argument("--duration", type=float, help="end the session after this many seconds of plant time")
    p.add_argument("--list-subjects", action="store_true")
    p.add_argument("--passive", type=float, help="override the subject's passive-muscle scale (calibration)")
    args = p.parse_args(argv)
    if args.list_subjects:
        print(json.dumps(SUBJECTS, indent=1))
        return 0
    if args.subject not in BY_NAME:
        log(f"unknown subject {args.subject!r}; known: {', '.join(BY_NAME)}")
        return 2
    # stdout carries only protocol lines: keep its descriptor for them and send
    # anything else that writes to descriptor 1 (C libraries) to stderr.
    sys.stdout.flush()
    proto = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    subject = dict(BY_NAME[args.subject])
    if args.passive is not None:
        subject["passive"] = args.passive
    plant = Plant(subject, seed=args.seed, noise=args.noise == "on")
    s = Stream(args.tcp, proto)
    s.send({"protocol": "limb-plant/1", "dt": DT, "name": f"myoarm_r, subject {args.subject}", "truth": TRUTH})
    answer = s.receive()
    if not answer:
        return 0
    try:
        msg = json.loads(answer, parse_constant=_reject_constant)
    except ValueError:
        s.send({"end": "handshake answer is not JSON"})
        return 3
    if not isinstance(msg, dict) or "error" in msg or msg.get("protocol") != "limb-plant/1":
        log(f"client refused: {answer.strip()}")
        return 0
    try:
        return loop(s, plant, args)
    except (BrokenPipeError, ConnectionError):
        return 0
    except Exception as e:  # an error of the plant itself: say so on the protocol, exit non-zero
        log(f"myoarm: internal error: {e!r}")
        try:
            s.send({"end": f"plant error: {e}"})
        except OSError:
            pass
        return 4


def loop(s, plant, args):
    while True:
        s.send({"frame": plant.frame(), "truth": plant.truth()})
        if args.duration is not None and plant.t >= args.duration - 1e-9:
            s.send({"end": f"duration {args.duration} s reached"})
            return 0
        line = s.receive()
        if not line:
            return 0
        try:
            msg = json.loads(line, parse_constant=_reject_constant)
            if not isinstance(msg, dict):
                raise ValueError("not an object")
            if "end" in msg:
                return 0
            cmd = msg.get("command")
            if not isinstance(cmd, dict):
                raise ValueError("expected a command")
            plant.command(cmd)
        except ValueError as e:
            s.send({"end": f"malformed command: {e}"})
            return 3
        plant.step()


if __name__ == "__main__":
    sys.exit(main())
