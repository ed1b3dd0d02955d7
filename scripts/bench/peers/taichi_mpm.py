#!/usr/bin/env python3
"""Peer MPM solver in Taichi: the scheme of our C++ CPU backend, re-written for comparison.

Reads one of our scene JSON files (the subset a box-seeded column collapse uses: grid,
gravity, flip_alpha, walls, material, particles as boxes, run.dt fixed) and runs a fixed
number of explicit MPM steps on Taichi's CPU backend in double precision:

  order    each step the particles are binned by block of 3x3x3 stencil-base cells (a
           counting sort), and G2P writes them in that order into a second copy of their
           fields, where the next step reads them nearly in turn
  P2G      quadratic B-splines (paper Eq 2); node mass, momentum m v and m v + dt f_int with
           f_int = -J V0 sigma grad w (Eq 14 without external forces); the blocks of one of
           eight parity colours in parallel, a block's particles in turn, so that no two threads
           add to one node and the adds are plain loads and stores (no atomics); a node's seven
           values in one record of eight
  grid     v_old = p/m, v_new = (p + dt f)/m + dt g; walls: inward normal removed, Coulomb
           friction with the removed normal speed (GridBoundary.hpp)
  G2P      FLIP/PIC blend alpha (Eq 4), x += dt v_PIC clamped to the admissible box,
           L = sum v_new (x) grad w, J *= det(I + dt L)
  stress   hypoelastic Jaumann trial stress and the mu(I) return map with the gasified state
           (Appendix B, as in Constitutive.hpp)

    python taichi_mpm.py scene.json --steps 200 --threads 2

Prints one JSON line: particles, steps, seconds (steps 3..N; steps 1 and 2 include the
compilation of the kernels of the two copies and are reported apart), particle_updates_per_s, bytes_per_particle (the fields'
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
    """The blend of one step of length dt (pkg/mpm/FlipBlend.hpp, FlipBlend::alphaFor): a PIC
    viscosity flip_viscosity [m^2/s] (default 0.005) hands PIC the share 4 nu dt / dx^2 and keeps
    the rest of FLIP; flip_alpha per flip_reference_dt of simulated time, or per step with "step"."""
    if "flip_reference_dt" not in s:
        return max(0.0, 1.0 - 4.0 * float(s.get("flip_viscosity", 0.005)) * dt / float(s["grid"]["dx"]) ** 2)
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
    nb = [c // 3 + 1 for c in cells]  # blocks of 3x3x3 stencil bases per axis
    nblocks = nb[0] * nb[1] * nb[2]

    F = {}

    def particle_fields(tag):
        """One copy of the particle state (G2P writes the other copy)."""
        P = {}
        P["x"] = ti.Vector.field(3, f64, n)
        P["v"] = ti.Vector.field(3, f64, n)
        P["s"] = ti.Vector.field(6, f64, n)  # Cauchy stress, xx yy zz yz xz xy, tension positive
        P["J"] = ti.field(f64, n)
        P["m"] = ti.field(f64, n)
        P["vol0"] = ti.field(f64, n)
        P["gdp"] = ti.field(f64, n)
        P["phase"] = ti.field(ti.u8, n)
        for k, f in P.items():
            F[k + tag] = f
        return P

    PA, PB = particle_fields("_a"), particle_fields("_b")
    # node record: 0..2 momentum, then old velocity; 3 mass; 4..6 momentum + dt force, then new
    # velocity; 7 unused (a node is one 64-byte line)
    grid = ti.Vector.field(8, f64, nodes)
    block = ti.field(ti.i32, n)       # block of each particle, this step
    order = ti.field(ti.i32, n)       # particles by block
    count = ti.field(ti.i32, nblocks)
    start = ti.field(ti.i32, nblocks + 1)
    fill = ti.field(ti.i32, nblocks)
    bad = ti.field(ti.i32, ())
    red = ti.field(f64, 4)
    F.update(grid=grid, block=block, order=order, count=count, start=start, fill=fill, bad=bad, red=red)
    mass_eps = ti.field(f64, ())

    @ti.func
    def stencil(xp):
        g = (xp - org) * inv_dx
        b = ti.floor(g - 0.5)
        f = g - b  # in [0.5, 1.5): distance to the first node of the stencil, in cells
        a0, a1, a2 = 1.5 - f, f - 1.0, f - 0.5
        # row k, column axis: weight and d/dg of the weight of stencil node k
        w = ti.Matrix.rows([0.5 * a0 * a0, 0.75 - a1 * a1, 0.5 * a2 * a2])
        dw = ti.Matrix.rows([-a0, -2.0 * a1, a2])
        return ti.cast(b, ti.i32), w, dw

    @ti.kernel
    def clear_grid():
        for I in ti.grouped(grid):
            grid[I] = ti.Vector.zero(f64, 8)

    @ti.kernel
    def scan():
        ti.loop_config(serialize=True)
        for b in range(nblocks):
            start[b + 1] = start[b] + count[b]
        for b in fill:
            fill[b] = start[b]

    @ti.kernel
    def place():
        for p in block:
            order[ti.atomic_add(fill[block[p]], 1)] = p

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
        for I in ti.grouped(grid):
            r = grid[I]
            mn = r[3]
            if mn > mass_eps[None]:
                inv = 1.0 / mn
                vn = ti.Vector([r[4], r[5], r[6]]) * inv + dt * gravity
                for a in ti.static(range(3)):
                    if I[a] <= WALL_LAYER:
                        vn = wall(vn, a, -1.0, friction[2 * a])
                    if I[a] >= cells[a] - WALL_LAYER:
                        vn = wall(vn, a, 1.0, friction[2 * a + 1])
                grid[I] = ti.Vector([r[0] * inv, r[1] * inv, r[2] * inv, mn, vn[0], vn[1], vn[2], 0.0])
            else:
                grid[I] = ti.Vector.zero(f64, 8)

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

    # the eight parity colours of the blocks: parity per axis and blocks of that parity per axis
    PARITY = [((c >> 2) & 1, (c >> 1) & 1, c & 1) for c in range(8)]
    COUNT = [tuple((nb[d] - par[d] + 1) // 2 for d in range(3)) for par in PARITY]

    def kernels(A, B):
        """The kernels of a step that reads particle copy A and writes copy B."""
        x, v, s, J, m, vol0 = A["x"], A["v"], A["s"], A["J"], A["m"], A["vol0"]
        xB, vB, sB, JB, mB, vol0B, gdpB, phaseB = (B[k] for k in ("x", "v", "s", "J", "m", "vol0", "gdp", "phase"))

        @ti.kernel
        def bin_particles():
            for b in count:
                count[b] = 0
            for p in x:
                base = ti.cast(ti.floor((x[p] - org) * inv_dx - 0.5), ti.i32) // 3
                b = (base[0] * nb[1] + base[1]) * nb[2] + base[2]
                block[p] = b
                ti.atomic_add(count[b], 1)

        @ti.kernel
        def p2g(dt: f64, px: ti.i32, py: ti.i32, pz: ti.i32, cx: ti.i32, cy: ti.i32, cz: ti.i32):
            for i in range(cx * cy * cz):
                bz = 2 * (i % cz) + pz
                by = 2 * ((i // cz) % cy) + py
                bx = 2 * (i // (cz * cy)) + px
                b = (bx * nb[1] + by) * nb[2] + bz
                for q in range(start[b], start[b + 1]):
                    p = order[q]
                    base, w, dw = stencil(x[p])
                    mp = m[p]
                    c = -dt * J[p] * vol0[p]
                    sp = s[p]
                    S = ti.Matrix([[sp[0], sp[5], sp[4]], [sp[5], sp[1], sp[3]], [sp[4], sp[3], sp[2]]],
                                  dt=f64) * c
                    mv = mp * v[p]
                    for ii, jj, kk in ti.static(ti.ndrange(3, 3, 3)):
                        wt = w[ii, 0] * w[jj, 1] * w[kk, 2]
                        gw = ti.Vector([dw[ii, 0] * w[jj, 1] * w[kk, 2], w[ii, 0] * dw[jj, 1] * w[kk, 2],
                                        w[ii, 0] * w[jj, 1] * dw[kk, 2]], dt=f64) * inv_dx
                        node = base + ti.Vector([ii, jj, kk])
                        mom = wt * mv
                        f = S @ gw
                        # this block alone adds to these nodes in this colour: a plain add
                        grid[node] = grid[node] + ti.Vector([mom[0], mom[1], mom[2], wt * mp, mom[0] + f[0],
                                                             mom[1] + f[1], mom[2] + f[2], 0.0])

        @ti.kernel
        def g2p(dt: f64):
            for q in order:
                p = order[q]
                base, w, dw = stencil(x[p])
                v_pic = ti.Vector.zero(f64, 3)
                dv = ti.Vector.zero(f64, 3)
                L = ti.Matrix.zero(f64, 3, 3)
                for i, j, k in ti.static(ti.ndrange(3, 3, 3)):
                    wt = w[i, 0] * w[j, 1] * w[k, 2]
                    gw = ti.Vector([dw[i, 0] * w[j, 1] * w[k, 2], w[i, 0] * dw[j, 1] * w[k, 2],
                                    w[i, 0] * w[j, 1] * dw[k, 2]], dt=f64) * inv_dx
                    r = grid[base + ti.Vector([i, j, k])]
                    vn = ti.Vector([r[4], r[5], r[6]])
                    v_pic += wt * vn
                    dv += wt * (vn - ti.Vector([r[0], r[1], r[2]]))
                    L += vn.outer_product(gw)
                vp = alpha * (v[p] + dv) + (1.0 - alpha) * v_pic
                xp = ti.min(ti.max(x[p] + dt * v_pic, lo), hi)
                Fm = ti.Matrix.identity(f64, 3) + dt * L
                Jn = J[p] * Fm.determinant()
                xB[q] = xp
                vB[q] = vp
                JB[q] = Jn
                mB[q] = m[p]
                vol0B[q] = vol0[p]
                if Jn > 0:
                    sp = s[p]
                    sig = ti.Matrix([[sp[0], sp[5], sp[4]], [sp[5], sp[1], sp[3]], [sp[4], sp[3], sp[2]]], dt=f64)
                    out, ph, gd = update_stress(sig, L, dt, m[p] / (Jn * vol0[p]))
                    sB[q] = ti.Vector([out[0, 0], out[1, 1], out[2, 2], out[1, 2], out[0, 2], out[0, 1]], dt=f64)
                    phaseB[q] = ti.cast(ph, ti.u8)
                    gdpB[q] = gd
                else:
                    sB[q] = s[p]
                    phaseB[q] = ti.cast(2, ti.u8)
                    gdpB[q] = 0.0
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
            bin_particles()
            scan()
            place()
            clear_grid()
            for par, cnt in zip(PARITY, COUNT):  # one colour after another
                if cnt[0] * cnt[1] * cnt[2]:
                    p2g(dt, *par, *cnt)
            grid_update(dt)
            g2p(dt)

        return step, reduce

    steps = [kernels(PA, PB), kernels(PB, PA)]
    state = {"k": 0}

    def step(dt):
        steps[state["k"]][0](dt)
        state["k"] ^= 1

    def reduce():
        steps[state["k"]][1]()  # the copy the last step wrote

    return F, PA, mass_eps, step, reduce


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
    if args.steps < 3:
        ap.error("--steps must be >= 3 (the first two steps compile the kernels and are timed apart)")

    import taichi as ti
    kw = dict(arch=ti.cpu, default_fp=ti.f64, default_ip=ti.i32, log_level=ti.WARN)
    if args.threads > 0:
        kw["cpu_max_num_threads"] = args.threads
    ti.init(**kw)

    sc = load_scene(args.scene)
    xs, vs, ms, vols = seed(sc)
    n = len(ms)
    F, P, mass_eps, step, reduce = build(sc, n, ti)
    P["x"].from_numpy(xs)
    P["v"].from_numpy(vs)
    P["m"].from_numpy(ms)
    P["vol0"].from_numpy(vols)
    P["J"].fill(1.0)
    mass_eps[None] = 1e-12 * float(ms.mean())
    del xs, vs, ms, vols
    dt = sc["dt"]

    t0 = time.perf_counter()
    for _ in range(2):  # one step per copy of the particles: each compiles its kernels
        step(dt)
    ti.sync()
    warmup = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(args.steps - 2):
        step(dt)
    ti.sync()
    seconds = time.perf_counter() - t0
    if F["bad"][None]:
        sys.exit("taichi_mpm: %d particle(s) inverted or above the blow-up speed" % F["bad"][None])
    reduce()
    out = {
        "solver": "taichi-%s-cpu-double" % ".".join(map(str, ti.__version__)),
        "particles": n, "steps": args.steps, "warmup_seconds": warmup, "seconds": seconds,
        "particle_updates_per_s": n * (args.steps - 2) / seconds,
        "bytes_per_particle": field_bytes(F, ti) / n,
        "max_rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
        "threads": args.threads, "dt": dt,
        "front_x": float(F["red"][0]), "height_z": float(F["red"][1]), "kinetic_energy": float(F["red"][2]),
    }
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
