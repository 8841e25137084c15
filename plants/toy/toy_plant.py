#!/usr/bin/env python3
"""A scripted toy plant speaking limb-plant/1 (../../../shared/spec/external-plant.md).

It is plant.md's reference plant written again, independently, in plain
Python (no numpy): a passive planar two-link arm lying on a table, lifted
through plant.md's Cartesian impedance at the grasp, integrated by
semi-implicit Euler at 0.5 ms, two steps per 1 ms frame, with plant.md's
measurement noise (seeded). It serves the client's tests and shows what
any external simulator has to do.

    toy_plant.py [--l1 M] [--l2 M] [--seed N] [--noise on|off] [--tcp PORT]
                 [--fault KIND --at N]

--tcp PORT listens on 127.0.0.1:PORT for one client (0: a free port; the
port is printed on stderr as "listening on PORT"); else stdin/stdout.
--t0 T starts the plant's clock at T; --exit-code N exits N after limb's
end. --fault makes the plant misbehave at frame N (1 = the first frame), to
test the client: malformed, missing, nan, string, truth, time, eof,
silent, long, unknown, extra_key (an unknown key, which must be ignored),
end (the plant ends the session itself); handshake faults (N ignored):
protocol, dt, handshake_silent.
"""
import argparse
import json
import math
import random
import socket
import sys
import time

G = 9.81
M1, M2 = 1.55, 1.317
LAM = (2.0, 2.0, 0.05)
K = (200.0, 200.0, 10.0)
D = tuple(2.0 * 2.0 * math.sqrt(k * lam) for k, lam in zip(K, LAM))
STEP = 0.0005
DT = 0.001
TRUTH = ["q1", "q2", "elbow_x", "elbow_z", "shoulder_x", "shoulder_z", "l1", "l2"]


def solve(a, b):
    """Solves the small dense system a x = b by Gaussian elimination with pivoting."""
    n = len(b)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        m[c], m[p] = m[p], m[c]
        for r in range(c + 1, n):
            f = m[r][c] / m[c][c]
            for k in range(c, n + 1):
                m[r][k] -= f * m[c][k]
    x = [0.0] * n
    for r in range(n - 1, -1, -1):
        x[r] = (m[r][n] - sum(m[r][k] * x[k] for k in range(r + 1, n))) / m[r][r]
    return x


class Arm:
    def __init__(self, l1, l2):
        self.l1, self.l2 = l1, l2
        self.q = [0.0, 0.0]
        self.qd = [0.0, 0.0]
        self.sp = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # pose, velocity, acceleration
        self.impedance = True
        self.wrench = (0.0, 0.0, 0.0)
        self.f_ext = (0.0, 0.0, 0.0)

    def pose(self):
        l1, l2 = self.l1, self.l2
        q1, psi = self.q[0], self.q[0] + self.q[1]
        ex, ez = l2 + l1 - l1 * math.cos(q1), l1 * math.sin(q1)
        return (ex - l2 * math.cos(psi), ez + l2 * math.sin(psi), psi), (ex, ez)

    def step(self):
        l1, l2 = self.l1, self.l2
        q1, q2 = self.q
        q1d, q2d = self.qd
        psi, psid = q1 + q2, q1d + q2d
        s1, c1, sp, cp = math.sin(q1), math.cos(q1), math.sin(psi), math.cos(psi)
        J = [[l1 * s1 + l2 * sp, l2 * sp], [l1 * c1 + l2 * cp, l2 * cp], [1.0, 1.0]]
        jdqd = [l1 * c1 * q1d**2 + l2 * cp * psid**2, -l1 * s1 * q1d**2 - l2 * sp * psid**2, 0.0]
        x, _ = self.pose()
        v = [J[i][0] * q1d + J[i][1] * q2d for i in range(3)]
        c2 = l2 / 2
        i1, i2 = M1 * l1**2 / 12, M2 * l2**2 / 12
        m11 = i1 + M1 * (l1 / 2) ** 2 + i2 + M2 * (l1**2 + c2**2 + 2 * l1 * c2 * math.cos(q2))
        m12 = i2 + M2 * (c2**2 + l1 * c2 * math.cos(q2))
        m22 = i2 + M2 * c2**2
        h = M2 * l1 * c2 * math.sin(q2)
        cor = [-h * (2 * q1d * q2d + q2d**2), h * q1d**2]
        gh = [M1 * G * l1 / 2 * c1 + M2 * G * (l1 * c1 + c2 * cp), M2 * G * c2 * cp]
        sp_ = self.sp
        if self.impedance:
            f0 = [-(LAM[i] * (jdqd[i] - sp_[6 + i]) + D[i] * (v[i] - sp_[3 + i]) + K[i] * (x[i] - sp_[i])) for i in range(3)]
        else:
            f0 = [-LAM[i] * jdqd[i] + self.wrench[i] for i in range(3)]
        mt = [[m11, m12], [m12, m22]]
        for a in range(2):
            for b in range(2):
                mt[a][b] += sum(J[i][a] * LAM[i] * J[i][b] for i in range(3))
        rhs = [sum(J[i][a] * f0[i] for i in range(3)) - cor[a] - gh[a] for a in range(2)]
        rows = [[1.0, 0.0], [1.0, 1.0]]
        bound = [q1, psi]
        vel = [q1d, psid]
        at_bound = [abs(bound[k]) <= 1e-12 and vel[k] <= 0.0 for k in range(2)]
        qdd = None
        for active in ([], [0], [1], [0, 1]):
            if any(not at_bound[k] for k in active):
                continue
            n = 2 + len(active)
            a = [[0.0] * n for _ in range(n)]
            b = rhs[:] + [0.0] * len(active)
            for r in range(2):
                a[r][0], a[r][1] = mt[r]
            for j, k in enumerate(active):
                for c in range(2):
                    a[c][2 + j] = -rows[k][c]
                    a[2 + j][c] = rows[k][c]
            sol = solve(a, b)
            lam = sol[2:]
            acc = sol[:2]
            if any(l < 0 for l in lam):
                continue
            if any(at_bound[k] and k not in active and rows[k][0] * acc[0] + rows[k][1] * acc[1] < 0 for k in range(2)):
                continue
            qdd = acc
            for k in active:
                if k == 0:
                    self.q[0], self.qd[0] = 0.0, 0.0
                else:
                    self.q[1], self.qd[1] = -self.q[0], -self.qd[0]
            break
        if qdd is None:
            qdd = solve(mt, rhs)
        q1d, q2d = self.qd
        xdd = [J[i][0] * qdd[0] + J[i][1] * qdd[1] + jdqd[i] for i in range(3)]
        if self.impedance:
            force = [-LAM[i] * (xdd[i] - sp_[6 + i]) - D[i] * (v[i] - sp_[3 + i]) - K[i] * (x[i] - sp_[i]) for i in range(3)]
        else:
            force = [-LAM[i] * xdd[i] + self.wrench[i] for i in range(3)]
        self.f_ext = tuple(-f for f in force)
        self.qd = [q1d + qdd[0] * STEP, q2d + qdd[1] * STEP]
        self.q = [self.q[0] + self.qd[0] * STEP, self.q[1] + self.qd[1] * STEP]
        if self.q[0] < 0:
            self.q[0], self.qd[0] = 0.0, max(self.qd[0], 0.0)
        if self.q[0] + self.q[1] < 0:
            self.q[1] = -self.q[0]
            self.qd[1] = max(self.qd[0] + self.qd[1], 0.0) - self.qd[0]


class Stream:
    def __init__(self, args):
        if args.tcp is None:
            self.inp, self.out = sys.stdin, sys.stdout
        else:
            server = socket.socket()
            server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            server.bind(("127.0.0.1", args.tcp))
            server.listen(1)
            print(f"listening on {server.getsockname()[1]}", file=sys.stderr, flush=True)
            conn, _ = server.accept()
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.inp = conn.makefile("r", encoding="utf-8")
            self.out = conn.makefile("w", encoding="utf-8")

    def send(self, text):
        self.out.write(text + "\n")
        self.out.flush()

    def receive(self):
        return self.inp.readline()


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--l1", type=float, default=0.30)
    p.add_argument("--l2", type=float, default=0.20)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--noise", choices=["on", "off"], default="on")
    p.add_argument("--tcp", type=int)
    p.add_argument("--fault")
    p.add_argument("--at", type=int, default=100)
    p.add_argument("--t0", type=float, default=0.0, help="the first frame's time [s]")
    p.add_argument("--exit-code", type=int, default=0, help="exit status after limb's end")
    args = p.parse_args()
    rng = random.Random(args.seed)
    noise = args.noise == "on"
    s = Stream(args)
    fault = args.fault
    handshake = {"protocol": "limb-plant/1", "dt": DT, "name": f"toy arm l1={args.l1} l2={args.l2}", "truth": TRUTH}
    if fault == "protocol":
        handshake["protocol"] = "limb-plant/2"
    if fault == "dt":
        handshake["dt"] = 0.0
    if fault == "handshake_silent":
        time.sleep(3600)
    s.send(json.dumps(handshake))
    answer = s.receive()
    if not answer or "error" in json.loads(answer):
        return 0
    arm = Arm(args.l1, args.l2)
    held = None
    frame_no = 0
    t = args.t0
    while True:
        frame_no += 1
        (x, z, psi), (ex, ez) = arm.pose()
        f = arm.f_ext
        n = (lambda sd: rng.gauss(0.0, sd)) if noise else (lambda sd: 0.0)
        frame = {"t": t, "x": x + n(1e-4), "y": n(1e-4), "z": z + n(1e-4), "psi": psi + n(1e-3),
                 "fx": f[0] + n(0.5), "fy": n(0.5), "fz": f[1] + n(0.5), "ty": f[2] + n(0.025)}
        truth = {"q1": arm.q[0], "q2": arm.q[1], "elbow_x": ex, "elbow_z": ez,
                 "shoulder_x": args.l1 + args.l2, "shoulder_z": 0.0, "l1": args.l1, "l2": args.l2}
        message = {"frame": frame, "truth": truth}
        if fault and frame_no == args.at:
            if fault == "malformed":
                s.send('{"frame": {"t": ')
            elif fault == "missing":
                del frame["fz"]
            elif fault == "nan":
                frame["fx"] = float("nan")
            elif fault == "string":
                frame["fx"] = "1.0"
            elif fault == "truth":
                del truth["elbow_z"]
            elif fault == "time":
                frame["t"] = t - DT
            elif fault == "eof":
                return 0
            elif fault == "silent":
                time.sleep(3600)
            elif fault == "long":
                message["pad"] = "x" * 70000
            elif fault == "unknown":
                message = {"hello": 1}
            elif fault == "extra_key":
                frame["vx"] = 0.0
                message["comment"] = "an unknown key"
            elif fault == "end":
                s.send(json.dumps({"end": "toy plant ends here"}))
                return 0
        if not (fault == "malformed" and frame_no == args.at):
            s.send(json.dumps(message))
        line = s.receive()
        if not line:
            return args.exit_code
        msg = json.loads(line)
        if "end" in msg:
            return args.exit_code
        cmd = msg.get("command")
        if cmd is None:
            s.send(json.dumps({"end": "expected a command"}))
            return 3
        mode = cmd.get("mode")
        if "xd" in cmd:
            arm.impedance = True
            held = None
            arm.sp = tuple(float(cmd.get(k, 0.0)) for k in ("xd", "zd", "psid", "vxd", "vzd", "vpsid", "axd", "azd", "apsid"))
        elif mode == "hold":
            arm.impedance = True
            if held is None:
                held = arm.pose()[0]
            arm.sp = tuple(held) + (0.0,) * 6
        elif mode == "stop":
            arm.impedance = False
        arm.wrench = (float(cmd.get("fx", 0.0)), float(cmd.get("fz", 0.0)), float(cmd.get("ty", 0.0)))
        arm.step()
        arm.step()
        t = round(t + DT, 9)


if __name__ == "__main__":
    sys.exit(main())
