#!/usr/bin/env python3
"""one_element.py: ccx_hencky (build.sh) on one element, NLGEOM, against closed forms.

  python3 validation/calculix/umat/one_element.py [CCX] [WORKDIR]

1. confined compression of a C3D8 cube to the stretch l = 0.9 (elastic umat):
   Cauchy sigma_zz = (lambda + 2 mu) ln(l)/l, sigma_xx = lambda ln(l)/l;
2. the same on one CAX8 element (r in [1, 2] mm, u_r = 0: the hoop stretch is 1),
   through CalculiX's expansion of axisymmetric elements into 3D wedges;
3. Maxwell relaxation (C3D8): the stretch 0.9 reached in 1e-4 s (one increment), held
   for 1 s in fixed increments of 0.01 s (*VISCO, DIRECT): sigma_zz against backward
   Euler's closed form at the same increments, and against the exact exponential.
Prints one line per check with the worst relative error and PASS/FAIL (tolerance 5e-7: the
.dat prints stresses to 7 significant digits); exit 1 on a FAIL.
Constants: E = 20000 MPa, nu = 0.3, eta = 30000 MPa s (R1's).
"""
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
CCX = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "ccx_hencky")
WORK = sys.argv[2] if len(sys.argv) > 2 else "/tmp/umat-one-element"
E, NU, ETA = 20000.0, 0.3, 30000.0
LAM = E * NU / ((1 + NU) * (1 - 2 * NU))
MU = E / (2 * (1 + NU))
KAPPA = E / (3 * (1 - 2 * NU))
L = 0.9

CUBE_NODES = """*NODE, NSET=NALL
1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
5, 0, 0, 1
6, 1, 0, 1
7, 1, 1, 1
8, 0, 1, 1
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
*NSET, NSET=BOT
1, 2, 3, 4
*NSET, NSET=TOP
5, 6, 7, 8
*BOUNDARY
NALL, 1, 2
BOT, 3, 3
"""

CAX_NODES = """*NODE, NSET=NALL
1, 1.0, 0.0, 0
2, 2.0, 0.0, 0
3, 2.0, 1.0, 0
4, 1.0, 1.0, 0
5, 1.5, 0.0, 0
6, 2.0, 0.5, 0
7, 1.5, 1.0, 0
8, 1.0, 0.5, 0
*ELEMENT, TYPE=CAX8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
*NSET, NSET=BOT
1, 2, 5
*NSET, NSET=TOP
3, 4, 7
*BOUNDARY
NALL, 1, 1
BOT, 2, 2
"""


def material(constants):
    vals = ", ".join(f"{c:.12e}" for c in constants)
    return (
        "*MATERIAL, NAME=USERHENCKY\n"
        f"*USER MATERIAL, CONSTANTS={len(constants)}\n{vals}\n"
        "*DEPVAR\n6\n*SOLID SECTION, ELSET=EALL, MATERIAL=USERHENCKY\n"
    )


def run(name, deck):
    os.makedirs(WORK, exist_ok=True)
    with open(os.path.join(WORK, name + ".inp"), "w") as f:
        f.write(deck)
    with open(os.path.join(WORK, name + ".log"), "w") as log:
        subprocess.run([CCX, "-i", name], cwd=WORK, stdout=log, check=True,
                       env=dict(os.environ, OMP_NUM_THREADS="1"))
    with open(os.path.join(WORK, name + ".dat")) as f:
        return f.read()


def stresses(dat):
    """[(time, [[sxx, syy, szz, sxy, sxz, syz] per integration point])] of the .dat."""
    out, cur = [], None
    for line in dat.splitlines():
        s = line.strip()
        if s.startswith("stresses"):
            cur = (float(s.rsplit("time", 1)[1]), [])
            out.append(cur)
        elif s and cur is not None and not s[0].isalpha():
            v = s.split()
            if len(v) == 8:
                cur[1].append([float(x) for x in v[2:]])
        elif s:
            cur = None
    return out


failed = 0


def report(name, err, tol):
    global failed
    ok = err <= tol
    failed += 0 if ok else 1
    print(f"{name}: {err:.3e} (tol {tol:.0e}) {'PASS' if ok else 'FAIL'}")


# 1, 2: confined compression, elastic
szz_ref = (LAM + 2 * MU) * math.log(L) / L
sxx_ref = LAM * math.log(L) / L
for name, nodes in [("cube", CUBE_NODES), ("cax8", CAX_NODES)]:
    deck = (nodes + material([E, NU]) +
            "*STEP, NLGEOM, INC=100\n*STATIC\n0.1, 1.0, 1e-4, 0.1\n"
            f"*BOUNDARY\nTOP, {3 if name == 'cube' else 2}, {3 if name == 'cube' else 2}, {L - 1}\n"
            "*EL PRINT, ELSET=EALL\nS\n*END STEP\n")
    st = stresses(run(name, deck))
    t, pts = st[-1]
    zz = 2 if name == "cube" else 1  # CAX: x = r, y = z, z = hoop
    xx = 0 if name == "cube" else 2
    err = max(max(abs(p[zz] / szz_ref - 1), abs(p[xx] / sxx_ref - 1)) for p in pts)
    print(f"{name}: sigma_zz = {pts[0][zz]:.6f} MPa (closed form {szz_ref:.6f}), "
          f"lateral {pts[0][xx]:.6f} ({sxx_ref:.6f}), {len(pts)} points, t = {t}")
    report(f"{name} confined compression to l = {L}, elastic", err, 5e-7)

# 3: Maxwell relaxation
DT, T_HOLD, T_JUMP = 0.01, 1.0, 1e-4
deck = (CUBE_NODES + material([E, NU, ETA]) +
        "*AMPLITUDE, NAME=JUMP, TIME=TOTAL TIME\n0, 0\n"
        f"{T_JUMP:.6e}, 1\n10, 1\n"
        "*STEP, NLGEOM, INC=100\n*VISCO, CETOL=1.0, DIRECT\n"
        f"{T_JUMP:.6e}, {T_JUMP:.6e}\n"
        f"*BOUNDARY, AMPLITUDE=JUMP\nTOP, 3, 3, {L - 1}\n*END STEP\n"
        "*STEP, NLGEOM, INC=1000\n*VISCO, CETOL=1.0, DIRECT\n"
        f"{DT}, {T_HOLD}\n"
        "*EL PRINT, ELSET=EALL\nS\n*END STEP\n")
st = stresses(run("relax", deck))
tau = ETA / (2 * MU)
p = KAPPA * math.log(L)
s_dev = 2 * MU * (2.0 / 3.0) * math.log(L) / (1 + 2 * MU * T_JUMP / ETA)
err_be = err_exp = 0.0
for n, (t, pts) in enumerate(st, start=1):
    # Cauchy sigma_zz = T_zz / l (J = l, T_zz = l^2 S_zz, sigma_zz = l S_zz)
    be = (p + s_dev / (1 + 2 * MU * DT / ETA) ** n) / L
    ex = (p + s_dev * math.exp(-(t - T_JUMP) / tau)) / L
    for q in pts:
        err_be = max(err_be, abs(q[2] / be - 1))
        err_exp = max(err_exp, abs(q[2] / ex - 1))
print(f"relax: {len(st)} increments to t = {st[-1][0]} s; sigma_zz(end) = "
      f"{st[-1][1][0][2]:.6f} MPa, backward Euler {be:.6f}, exact {ex:.6f}")
report("Maxwell relaxation vs backward Euler at the same increments", err_be, 5e-7)
print(f"Maxwell relaxation vs the exact exponential (dt = {DT} s, first order): "
      f"{err_exp:.3e}")
sys.exit(1 if failed else 0)
