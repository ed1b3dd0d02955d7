#!/usr/bin/env python3
"""Peer MPM solver in Taichi: the scheme of our C++ CPU backend, re-written for comparison.

Reads one of our scene JSON files (the subset a box-seeded column collapse uses: grid,
gravity, flip_alpha, walls, material, particles as boxes, run.dt fixed) and runs a fixed
number of explicit MPM steps on Taichi's CPU backend in double precision:

  P2G      quadratic B-splines (paper Eq 2); node mass, momentum m v and m v + dt f_int with
           f_int = -J V0 sigma grad w (Eq 14 without external forces)
  grid     v_old = p/m, v_new = (p + dt f)/m + dt g; walls: inward normal removed, Coulomb
           friction with the removed normal speed (GridBoundary.hpp)
  G2P      FLIP/PIC blend alpha (Eq 4), x += dt v_PIC clamped to the admissible box,
           L = sum v_new (x) grad w, J *= det(I + dt L)
  stress   hypoelastic Jaumann trial stress and the mu(I) return map with the gasified state
           (Appendix B, as in Constitutive.hpp)

    python taichi_mpm.py scene.json --steps 200 --threads 2

Prints one JSON line: particles, steps, seconds (steps 2..N; step 1 includes the kernels'
compilation and is reported apart), particle_updates_per_s, bytes_per_particle (the fields'
bytes / particles), max_rss_bytes, and the final front_x, height_z, kinetic_energy, so that
a caller can check that both solvers computed the same flow.
"""
import argparse
import json
import math
import resource
import sys
import time

import numpy as np

WALL_LAYER = 2  # cells of each wall's node layer; material points stay this far inside


def load_scene(path):
    with open(path) as f:
        s = json.load(f)
    g = s["grid"]
    dx = float(g["dx"])
    cells = [int(c) for c in g["cells"]]
    origin = [float(o) for o in g.get("origin", [0, 0, 0])]
    grav = s.get("gravity", [0, 0, -9.81])
    if isinstance(grav, dict):
        a = math.radians(float(grav.get("incline_deg", 0)))
        grav = [grav["g"] * math.sin(a), 0.0, -grav["g"] * math.cos(a)]
    friction = [0.0] * 6
    for i, name in enumerate(["-x", "+x", "-y", "+y", "-z", "+z"]):
        w = s.get("walls", {}).get(name, "free")
        friction[i] = 0.0 if w == "free" else (-1.0 if w == "noslip" else float(w))
    m = s["material"]
    mat = dict(density=float(m["density"]), E=float(m["young_modulus"]), nu=float(m["poisson_ratio"]),
               mu_s=float(m["mu_s"]), mu_2=float(m["mu_2"]), I0=float(m.get("I0", 0.279)),
               d=float(m.get("grain_diameter", 0.002)), rho_s=float(m.get("solid_density", 2500)),
               rho_c=float(m.get("critical_density", 0)))
    dt = s["run"].get("dt", "auto")
    if not isinstance(dt, (int, float)):
        sys.exit("taichi_mpm: the scene needs a fixed run.dt (both solvers must take the same step)")
    boxes = []
    for b in s["particles"]:
        if "mesh" in b:
            sys.exit("taichi_mpm: mesh-seeded particles are not supported, use boxes")
        ppc = b.get("ppc", 8)
        if isinstance(ppc, int):
            k = round(ppc ** (1.0 / 3.0))
            ppc = [k, k, k]
        boxes.append((b["lo"], b["hi"], ppc, b.get("velocity", [0, 0, 0])))
    return dict(dx=dx, cells=cells, origin=origin, gravity=[float(x) for x in grav], friction=friction,
                alpha=stepBlend(s, float(dt)), mat=mat, dt=float(dt), boxes=boxes)


def stepBlend(s, dt):
    """The blend of one step of length dt (pkg/mpm/MpmTypes.hpp, MpmParams::flipAlphaFor): a PIC
    viscosity flip_viscosity [m^2/s] (default 0.005) keeps exp(-4 nu dt / dx^2) of FLIP;
    flip_alpha per flip_reference_dt of simulated time, or per step with "step"."""
    if "flip_reference_dt" not in s:
        return math.exp(-4.0 * float(s.get("flip_viscosity", 0.005)) * dt / float(s["grid"]["dx"]) ** 2)
    alpha, ref = float(s.get("flip_alpha", 0.99)), s["flip_reference_dt"]
    return alpha if ref == "step" else alpha ** (dt / float(ref))


def seed(sc):
    """Particles at the sub-cell centres of every cell whose centre lies in a box, in the
    order and with the mass and volume of pkg/mpm/Seeding.cpp seedBox."""
    dx, o = sc["dx"], sc["origin"]
    xs, vs, ms, vols = [], [], [], []
    for lo, hi, ppc, vel in sc["boxes"]:
        axes = []
        for d in range(3):
            c0 = math.ceil((lo[d] - o[d]) / dx - 0.5 - 1e-9)
            c1 = math.floor((hi[d] - o[d]) / dx - 0.5 + 1e-9)
            cell = np.arange(c0, c1 + 1)[:, None]
            sub = np.arange(ppc[d])[None, :]
            axes.append((o[d] + (cell + (sub + 0.5) / ppc[d]) * dx).ravel())
        # i, j, k outermost, then the sub-cell indices: same as the C++ loop nest up to a
        # permutation that only reorders particles (the sums over particles do not care).
        X, Y, Z = np.meshgrid(axes[0], axes[1], axes[2], indexing="ij")
        x = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
        n = ppc[0] * ppc[1] * ppc[2]
        vol = dx * dx * dx / n
        xs.append(x)
        vs.append(np.tile(np.asarray(vel, dtype=np.float64), (len(x), 1)))
        ms.append(np.full(len(x), sc["mat"]["density"] * vol))
        vols.append(np.full(len(x), vol))
    return np.concatenate(xs), np.concatenate(vs), np.concatenate(ms), np.concatenate(vols)


def build(sc, n, ti):
    f64 = ti.f64
    dx, cells, origin = sc["dx"], sc["cells"], sc["origin"]
    nodes = [c + 1 for c in cells]
    inv_dx = 1.0 / dx
    mat = sc["mat"]
    E, nu = mat["E"], mat["nu"]
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    G = E / (2 * (1 + nu))
    mu_s, mu_2 = mat["mu_s"], mat["mu_2"]
    xi = mat["I0"] / (mat["d"] * math.sqrt(mat["rho_s"]))
    rho_c = mat["rho_c"] if mat["rho_c"] > 0 else mat["density"]
    alpha = sc["alpha"]
    gravity = ti.Vector(sc["gravity"], dt=f64)
    friction = sc["friction"]
    lo = ti.Vector([origin[d] + WALL_LAYER * dx for d in range(3)], dt=f64)
    hi = ti.Vector([origin[d] + (cells[d] - WALL_LAYER) * dx for d in range(3)], dt=f64)
    org = ti.Vector(origin, dt=f64)
    cp = math.sqrt((lam + 2 * G) / mat["density"])
    max_speed = 1e3 * cp  # blow-up threshold of the C++ solver

    F = {}
    F["x"] = ti.Vector.field(3, f64, n)
    F["v"] = ti.Vector.field(3, f64, n)
    F["s"] = ti.Vector.field(6, f64, n)  # Cauchy stress, xx yy zz yz xz xy, tension positive
    F["J"] = ti.field(f64, n)
    F["m"] = ti.field(f64, n)
    F["vol0"] = ti.field(f64, n)
    F["gdp"] = ti.field(f64, n)
    F["phase"] = ti.field(ti.u8, n)
    F["gm"] = ti.field(f64, nodes)
    F["gp"] = ti.Vector.field(3, f64, nodes)  # momentum, then old velocity
    F["gq"] = ti.Vector.field(3, f64, nodes)  # momentum + dt force, then new velocity
    F["bad"] = ti.field(ti.i32, ())
    F["red"] = ti.field(f64, 4)
    x, v, s, J, m, vol0, gdp, phase = (F[k] for k in ("x", "v", "s", "J", "m", "vol0", "gdp", "phase"))
    gm, gp, gq, bad, red = F["gm"], F["gp"], F["gq"], F["bad"], F["red"]
    mass_eps = ti.field(f64, ())

    @ti.func
    def stencil(p):
        g = (x[p] - org) * inv_dx
        b = ti.floor(g - 0.5)
        f = g - b  # in [0.5, 1.5): distance to the first node of the stencil, in cells
        a0, a1, a2 = 1.5 - f, f - 1.0, f - 0.5
        # row k, column axis: weight and d/dg of the weight of stencil node k
        w = ti.Matrix.rows([0.5 * a0 * a0, 0.75 - a1 * a1, 0.5 * a2 * a2])
        dw = ti.Matrix.rows([-a0, -2.0 * a1, a2])
        return ti.cast(b, ti.i32), w, dw

    @ti.kernel
    def clear_grid():
        for I in ti.grouped(gm):
            gm[I] = 0.0
            gp[I] = ti.Vector.zero(f64, 3)
            gq[I] = ti.Vector.zero(f64, 3)

    @ti.kernel
    def p2g(dt: f64):
        for p in x:
            base, w, dw = stencil(p)
            mp = m[p]
            c = -dt * J[p] * vol0[p]
            sp = s[p]
            S = ti.Matrix([[sp[0], sp[5], sp[4]], [sp[5], sp[1], sp[3]], [sp[4], sp[3], sp[2]]], dt=f64) * c
            for i, j, k in ti.static(ti.ndrange(3, 3, 3)):
                wt = w[i, 0] * w[j, 1] * w[k, 2]
                gw = ti.Vector([dw[i, 0] * w[j, 1] * w[k, 2], w[i, 0] * dw[j, 1] * w[k, 2],
                                w[i, 0] * w[j, 1] * dw[k, 2]], dt=f64) * inv_dx
                node = base + ti.Vector([i, j, k])
                mom = wt * mp * v[p]
                gm[node] += wt * mp
                gp[node] += mom
                gq[node] += mom + S @ gw

    @ti.func
    def wall(vn, axis: ti.template(), sign: ti.template(), mu: ti.template()):
        a1, a2 = (axis + 1) % 3, (axis + 2) % 3
        into = vn[axis] * sign
        removed = 0.0
        if into > 0:
            removed = into
            vn[axis] = 0.0
        if ti.static(mu < 0):
            vn[a1] = 0.0
            vn[a2] = 0.0
        elif ti.static(mu > 0):
            if removed > 0:
                vt = ti.sqrt(vn[a1] * vn[a1] + vn[a2] * vn[a2])
                cap = mu * removed
                if vt <= cap:
                    vn[a1] = 0.0
                    vn[a2] = 0.0
                else:
                    fac = 1.0 - cap / vt
                    vn[a1] *= fac
                    vn[a2] *= fac
        return vn

    @ti.kernel
    def grid_update(dt: f64):
        for I in ti.grouped(gm):
            mn = gm[I]
            if mn > mass_eps[None]:
                inv = 1.0 / mn
                gp[I] = gp[I] * inv
                vn = gq[I] * inv + dt * gravity
                for a in ti.static(range(3)):
                    if I[a] <= WALL_LAYER:
                        vn = wall(vn, a, -1.0, friction[2 * a])
                    if I[a] >= cells[a] - WALL_LAYER:
                        vn = wall(vn, a, 1.0, friction[2 * a + 1])
                gq[I] = vn
            else:
                gm[I] = 0.0
                gp[I] = ti.Vector.zero(f64, 3)
                gq[I] = ti.Vector.zero(f64, 3)

    @ti.func
    def update_stress(sig, L, dt, rho):
        """Constitutive.hpp updateStress: returns (new stress, phase, plastic shear rate)."""
        out = ti.Matrix.zero(f64, 3, 3)
        ph = 2
        gd = 0.0
        if rho >= rho_c:
            D = 0.5 * (L + L.transpose())
            W = 0.5 * (L - L.transpose())
            tr = sig + dt * (lam * D.trace() * ti.Matrix.identity(f64, 3) + 2.0 * G * D + W @ sig - sig @ W)
            p_tr = -tr.trace() / 3.0
            if p_tr > 0:
                dev = tr + p_tr * ti.Matrix.identity(f64, 3)
                tau_tr = ti.sqrt(0.5 * (dev * dev).sum())
                S0 = mu_s * p_tr
                if tau_tr <= S0:
                    out = tr
                    ph = 0
                else:
                    S2 = mu_2 * p_tr
                    a1 = xi * G * dt * ti.sqrt(p_tr)
                    B = S2 + tau_tr + a1
                    H = S2 * tau_tr + S0 * a1
                    disc = ti.max(B * B - 4.0 * H, 0.0)
                    tau = 2.0 * H / (B + ti.sqrt(disc))
                    gd = (tau_tr - tau) / (G * dt)
                    scale = tau / tau_tr
                    out = scale * tr + (scale - 1.0) * p_tr * ti.Matrix.identity(f64, 3)
                    ph = 1
        return out, ph, gd

    @ti.kernel
    def g2p(dt: f64):
        for p in x:
            base, w, dw = stencil(p)
            v_pic = ti.Vector.zero(f64, 3)
            dv = ti.Vector.zero(f64, 3)
            L = ti.Matrix.zero(f64, 3, 3)
            for i, j, k in ti.static(ti.ndrange(3, 3, 3)):
                wt = w[i, 0] * w[j, 1] * w[k, 2]
                gw = ti.Vector([dw[i, 0] * w[j, 1] * w[k, 2], w[i, 0] * dw[j, 1] * w[k, 2],
                                w[i, 0] * w[j, 1] * dw[k, 2]], dt=f64) * inv_dx
                node = base + ti.Vector([i, j, k])
                vn = gq[node]
                v_pic += wt * vn
                dv += wt * (vn - gp[node])
                L += vn.outer_product(gw)
            vp = alpha * (v[p] + dv) + (1.0 - alpha) * v_pic
            xp = ti.min(ti.max(x[p] + dt * v_pic, lo), hi)
            Fm = ti.Matrix.identity(f64, 3) + dt * L
            Jn = J[p] * Fm.determinant()
            x[p] = xp
            v[p] = vp
            J[p] = Jn
            if Jn > 0:
                sp = s[p]
                sig = ti.Matrix([[sp[0], sp[5], sp[4]], [sp[5], sp[1], sp[3]], [sp[4], sp[3], sp[2]]], dt=f64)
                out, ph, gd = update_stress(sig, L, dt, m[p] / (Jn * vol0[p]))
                s[p] = ti.Vector([out[0, 0], out[1, 1], out[2, 2], out[1, 2], out[0, 2], out[0, 1]], dt=f64)
                phase[p] = ti.cast(ph, ti.u8)
                gdp[p] = gd
            else:
                phase[p] = ti.cast(2, ti.u8)
                gdp[p] = 0.0
                bad[None] += 1
            if not vp.norm() <= max_speed:  # a NaN speed fails this test too
                bad[None] += 1

    @ti.kernel
    def reduce():
        red[0] = -1e300
        red[1] = -1e300
        red[2] = 0.0
        for p in x:
            ti.atomic_max(red[0], x[p][0])
            ti.atomic_max(red[1], x[p][2])
            red[2] += 0.5 * m[p] * v[p].dot(v[p])

    def step(dt):
        clear_grid()
        p2g(dt)
        grid_update(dt)
        g2p(dt)

    return F, mass_eps, step, reduce


def field_bytes(F, ti):
    """Bytes of the solver's fields, from their shapes and element types."""
    size = {ti.f64: 8, ti.i32: 4, ti.u8: 1}
    total = 0
    for f in F.values():
        n = int(np.prod(f.shape)) if f.shape else 1
        comps = f.n * f.m if hasattr(f, "n") else 1
        total += n * comps * size[f.dtype]
    return total


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="scene JSON (box particles, fixed run.dt)")
    ap.add_argument("--steps", type=int, required=True)
    ap.add_argument("--threads", type=int, default=0, help="CPU threads (default: Taichi's choice)")
    args = ap.parse_args()
    if args.steps < 2:
        ap.error("--steps must be >= 2 (the first step compiles the kernels and is timed apart)")

    import taichi as ti
    kw = dict(arch=ti.cpu, default_fp=ti.f64, default_ip=ti.i32, log_level=ti.WARN)
    if args.threads > 0:
        kw["cpu_max_num_threads"] = args.threads
    ti.init(**kw)

    sc = load_scene(args.scene)
    xs, vs, ms, vols = seed(sc)
    n = len(ms)
    F, mass_eps, step, reduce = build(sc, n, ti)
    F["x"].from_numpy(xs)
    F["v"].from_numpy(vs)
    F["m"].from_numpy(ms)
    F["vol0"].from_numpy(vols)
    F["J"].fill(1.0)
    mass_eps[None] = 1e-12 * float(ms.mean())
    del xs, vs, ms, vols
    dt = sc["dt"]

    t0 = time.perf_counter()
    step(dt)
    ti.sync()
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(args.steps - 1):
        step(dt)
    ti.sync()
    seconds = time.perf_counter() - t0
    if F["bad"][None]:
        sys.exit("taichi_mpm: %d particle(s) inverted or above the blow-up speed" % F["bad"][None])
    reduce()
    out = {
        "solver": "taichi-%s-cpu-double" % ".".join(map(str, ti.__version__)),
        "particles": n, "steps": args.steps, "first_step_seconds": first, "seconds": seconds,
        "particle_updates_per_s": n * (args.steps - 1) / seconds,
        "bytes_per_particle": field_bytes(F, ti) / n,
        "max_rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
        "threads": args.threads, "dt": dt,
        "front_x": float(F["red"][0]), "height_z": float(F["red"][1]), "kinetic_energy": float(F["red"][2]),
    }
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
