"""Analytic references and post-processing used by checks, examples and users. SI units."""
import math

G = 9.81  # default gravitational acceleration [m/s^2]


def slidingDistance(t, thetaDeg, mu, g=G):
    """Travel distance of a block sliding down an incline from rest, paper Eq 19:
    S_b(t) = t²/2 · (g sin θ − μ g cos θ); 0 when the block does not slide (μ ≥ tan θ)."""
    th = math.radians(thetaDeg)
    a = g * (math.sin(th) - mu * math.cos(th))
    return 0.5 * a * t * t if a > 0 else 0.0


def barrierForce(delta, R, kc):
    """Normal force of the log barrier (paper Eq 10 read as a force, docs/physics.md) [N]:
    F_n = −k_c δ [2 ln((R−δ)/R) − R/(R−δ) + 1], 0 ≤ δ < R, R = R_i + R_j."""
    if not 0 <= delta < R:
        raise ValueError("delta = %g m: must be in [0, R = %g m)" % (delta, R))
    return -kc * delta * (2.0 * math.log((R - delta) / R) - R / (R - delta) + 1.0)


def barrierStiffness(delta, R, kc):
    """Tangent stiffness k_n = dF_n/dδ of the barrier force [N/m]."""
    if not 0 <= delta < R:
        raise ValueError("delta = %g m: must be in [0, R = %g m)" % (delta, R))
    g = 2.0 * math.log((R - delta) / R) - R / (R - delta) + 1.0
    dg = -2.0 / (R - delta) - R / (R - delta) ** 2
    return -kc * (g + delta * dg)


def slidingDistanceElastic(t, thetaDeg, mu, Kt, mass, zeta=0.0, g=G):
    """Eq 19 for a block whose friction acts through a tangential spring-dashpot of total
    stiffness ``Kt`` [N/m] and damping ratio ``zeta`` [-], capped at μN (the SDEM law of
    Eqs 9 and 11), released from rest with the spring unloaded.

    Stage 1, stick: m x'' + c x' + Kt x = m g sin θ (c = 2 ζ √(m Kt)), until the spring-dashpot
    force Kt x + c x' reaches μ m g cos θ at t1; stage 2, Coulomb sliding at
    a = g (sin θ − μ cos θ) from (x1, v1). Equals Eq 19 for μ = 0 and tends to it as Kt → ∞.
    Rocking of the block is neglected. [m]"""
    th = math.radians(thetaDeg)
    gs, gc = g * math.sin(th), g * math.cos(th)
    a = gs - mu * gc
    if a <= 0:
        raise ValueError("thetaDeg = %g, mu = %g: the block does not slide (mu >= tan theta)" % (thetaDeg, mu))
    if not 0 <= zeta < 1:
        raise ValueError("zeta = %g: must be in [0, 1) (under-damped)" % zeta)
    w = math.sqrt(Kt / mass)
    wd = w * math.sqrt(1.0 - zeta * zeta)
    xs = gs / (w * w)  # static stretch under the slope load

    def stick(tt):  # position and velocity of the damped oscillator from rest
        e = math.exp(-zeta * w * tt)
        x = xs * (1.0 - e * (math.cos(wd * tt) + zeta * w / wd * math.sin(wd * tt)))
        v = xs * e * (w * w / wd) * math.sin(wd * tt)
        return x, v

    def spare(tt):  # Coulomb cap minus the spring-dashpot force per unit mass
        x, v = stick(tt)
        return mu * gc - (w * w * x + 2.0 * zeta * w * v)

    t1 = 0.0
    if mu > 0:
        hi = math.pi / wd  # the force peaks (above the cap: the block slides) within half a period
        lo = 0.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if spare(mid) > 0 else (lo, mid)
        t1 = 0.5 * (lo + hi)
    if t < t1:
        return stick(t)[0]
    x1, v1 = stick(t1)
    return x1 + v1 * (t - t1) + 0.5 * a * (t - t1) ** 2


def equilibriumOverlap(load, R, kc, contacts=1):
    """Overlap δ at which ``contacts`` equal barrier contacts carry ``load`` [N] together [m]
    (bisection on the monotonic barrier force)."""
    if load < 0:
        raise ValueError("load = %g N: must be >= 0" % load)
    lo, hi = 0.0, R * (1 - 1e-15)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if contacts * barrierForce(mid, R, kc) < load:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def tiltAndYaw(angle, axis):
    """A block's turn from its start split about the bed normal z (swing-twist): ``tilt`` [deg],
    the angle its own z axis leans from z (tipping, in [0, 180]), and ``yaw`` [deg], its twist
    about z (turning while it slides flat, in (−180, 180]). ``angle`` [rad] and ``axis`` (need
    not be unit) are the rotation from the start (YADE's ``ori.toAngleAxis()``). A cube tipped
    forward 30° has tilt 30, yaw 0; one turned 30° on the bed, tilt 0, yaw 30."""
    n = math.sqrt(sum(float(c) ** 2 for c in axis))
    if n == 0 or angle == 0:
        return 0.0, 0.0
    s, w = math.sin(0.5 * angle), math.cos(0.5 * angle)
    x, y, z = (float(c) / n * s for c in axis)
    tilt = math.degrees(math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y)))))
    yaw = math.degrees(2.0 * math.atan2(z, w))
    yaw = yaw - 360.0 if yaw > 180.0 else (yaw + 360.0 if yaw <= -180.0 else yaw)
    return tilt, yaw


BOX_FACES = ("-x", "+x", "-y", "+y", "-z", "+z")


def boxFaceLoads(contacts, rotation):
    """The flow's normal load on each face of a box-shaped block [N]: a dict with the six faces
    of its own frame ("-x" … "+z") and "edges", each the sum of F_n (Eq 10) of its contacts
    (``CoupledEngine.contacts(id)``, that block's). A face contact's normal is its face's
    outward normal; ``rotation`` is the block's orientation as a 3×3 matrix, body to world
    (YADE's ``state.ori.toRotationMatrix()``). Contacts at edges and corners go to "edges". In
    the flume frame a block placed square: "-x" faces upstream, "+z" is its top (paper §3.2.3:
    F_f split by face)."""
    loads = dict.fromkeys(BOX_FACES + ("edges",), 0.0)
    R = [[float(rotation[i, j]) for j in range(3)] for i in range(3)]
    for n, fn, feature in zip(contacts["normal"], contacts["normalForce"], contacts["feature"]):
        if feature != "face":
            loads["edges"] += float(fn)
            continue
        local = [sum(R[i][j] * float(n[i]) for i in range(3)) for j in range(3)]  # R^T n
        axis = max(range(3), key=lambda j: abs(local[j]))
        loads[("-" if local[axis] < 0 else "+") + "xyz"[axis]] += float(fn)
    return loads


def runoutLube(a):
    """Normalised runout ΔL/L_i of a quasi-2D granular column collapse of aspect ratio a:
    ≈ 1.2 a for a ≲ 1.8, ≈ 1.9 a^(2/3) above (Lube et al. 2005; Lajeunesse et al. 2005 report
    the same two regimes)."""
    return 1.2 * a if a < 1.8 else 1.9 * a ** (2.0 / 3.0)


def pointRadius(dx, ppc):
    """R_p0 of Eq 13 [m]: the radius of the sphere of a material point's initial volume, dx³/ppc
    for ``ppc`` points per cell of spacing ``dx`` [m]. What a point meets a block or a level set
    with (a LevelSet body's grid may be no coarser than it)."""
    return (3.0 * dx ** 3 / ppc / (4.0 * math.pi)) ** (1.0 / 3.0)


def froude(v, h, g=G):
    """Froude number Fr = v / √(g h) (paper §3.2.3 and §5)."""
    return v / math.sqrt(g * h)


def effectivePicViscosity(nu, dt, dx, share="linear"):
    """The viscosity a resolved flow feels from a FLIP/PIC blend given as the PIC viscosity ``nu``
    [m²/s], at a step ``dt`` [s] on a grid of spacing ``dx`` [m] [m²/s]. PIC's transfer diffuses a
    resolved velocity mode by (Δx²/4)∇² once per step, so a step that hands PIC the share s gives
    the flow s Δx²/(4Δt). ``share="linear"``: the blend of mpmsdem, s = x = 4 ν Δt/Δx² (at most 1:
    the stable step is at most Δx²/(4ν)), so the flow feels ν. ``share="exponential"``: the blend
    of runs recorded before it (docs/coupled-results.md, "Why the held viscosity does not hold"),
    s = 1 − e^(−x), so the flow felt ν (1 − e^(−x))/x, ν only while x ≪ 1 (a steady film matched
    it to 1.1–2.1 % at four spacings)."""
    for name, v in (("nu", nu), ("dt", dt), ("dx", dx)):
        if not (v > 0 and math.isfinite(v)):
            raise ValueError("%s = %r: must be finite and > 0" % (name, v))
    x = 4.0 * nu * dt / (dx * dx)
    if share == "linear":
        return nu * min(1.0, x) / x
    if share == "exponential":
        return nu * -math.expm1(-x) / x
    raise ValueError('share = %r: must be "linear" (the blend of mpmsdem) or "exponential" (before it)' % (share,))


def dynamicPressureCoefficient(Fr):
    """α_f = 10.8 Fr^(-1.3) (Thibert et al. 2008), used in the hydrodynamic model Eq 20."""
    return 10.8 * Fr ** -1.3


def hydrodynamicForce(rho, v, h, area, g=G):
    """Impact force of the hydrodynamic model, Eq 20: F = α_f ρ v² A, α_f from Fr = v/√(g h) [N]."""
    return dynamicPressureCoefficient(froude(v, h, g)) * rho * v * v * area


def froudeDistance(v, L0, g=G):
    """Fr1 = v / √(g L0), the Froude number on the block's distance from the source (paper §5)."""
    return v / math.sqrt(g * L0)


def staticImpactForce(rho, h, area, k=1.0, g=G):
    """Hydrostatic (static) impact force 0.5 k ρ g h A of a flow of depth ``h`` [m] and bulk
    density ``rho`` [kg/m³] on an area ``area`` [m²]; ``k`` is the static pressure coefficient
    (paper §5, after Ng et al. 2021; 1: no internal shear strength) [N]."""
    return 0.5 * k * rho * g * h * area


def wallSuperposedForce(rho, v, h, width, thetaDeg, k=1.0, alpha=1.0, g=G):
    """Force on a wall across the whole width of a flow of depth ``h`` [m] and depth-averaged
    speed ``v`` [m/s] on a slope of ``thetaDeg`` [deg], as design guides superpose it: the
    momentum flux brought to rest, α ρ v² h w, on top of the earth-pressure load of the
    arriving depth, ½ k ρ g cosθ h² w [N]. α = 1: all the incoming momentum destroyed."""
    return (alpha * rho * v * v * h + 0.5 * k * rho * g * math.cos(math.radians(thetaDeg)) * h * h) * width


def reflectedBoreDepth(Fr):
    """Depth ratio r = h₂/h of the bore that a wall across the whole width sends upstream into a
    steady flow of Froude number ``Fr`` = v/√(g′ h), the material behind the bore at rest. Mass,
    h (v + c) = h₂ c, and momentum, h (v + c)² + ½ g′ h² = h₂ c² + ½ g′ h₂², across the bore
    moving upstream at c give Fr² = (r − 1)² (r + 1) / (2 r), whose root r > 1 this returns
    (bisection; the right side grows monotonically from 0 at r = 1). Fr > 0."""
    if not (Fr > 0 and math.isfinite(Fr)):
        raise ValueError("Fr = %r: must be > 0 and finite" % (Fr,))
    f = lambda r: (r - 1.0) ** 2 * (r + 1.0) / (2.0 * r) - Fr * Fr  # noqa: E731
    lo, hi = 1.0, 2.0
    while f(hi) < 0:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) < 0 else (lo, mid)
    return 0.5 * (lo + hi)


def reflectedBoreForce(rho, v, h, width, thetaDeg, k=1.0, g=G):
    """Force on a wall across the whole width once the reflected bore of
    :func:`reflectedBoreDepth` has formed [N]: the earth-pressure load of the material at rest
    behind it, ½ ρ g′ h₂² w, with g′ = k g cosθ (``k``: the lateral pressure coefficient, 1 for
    a fluid) and Fr = v/√(g′ h). A frictionless shallow-water balance, no overflow: the skeleton
    that granular jump and dead-zone models refine, not a granular result by itself."""
    gp = k * g * math.cos(math.radians(thetaDeg))
    r = reflectedBoreDepth(v / math.sqrt(gp * h))
    return 0.5 * rho * gp * (r * h) ** 2 * width


def impactForceRatio(Fr, k=1.6, alphaF=0.18):
    """F_peak / F_static = 1 + 2 α_f Fr² / k, paper Eq 21 (Ng et al. 2021): the peak as the
    hydrodynamic force of Eq 20 on top of the static one, the static force 0.5 k ρ g h_f A.
    Defaults: the paper's fit to its §5 study (k = 1.6, α_f = 0.18); k = α_f = 1 is the
    paper's theoretical bound. Accepts a number or a numpy array of Froude numbers."""
    return 1.0 + 2.0 * alphaF * Fr ** 2 / k


def fitImpactForceRatio(Fr, ratio, k=1.6):
    """Least-squares fit of Eq 21 to measured F_peak/F_static against Fr. Only 2 α_f / k is
    determined by such data, so α_f is returned for the given static coefficient ``k``
    (default the paper's 1.6). Returns dict(alphaF, k, slope = 2 α_f / k, rms: root mean
    square residual of the ratio, n)."""
    import numpy as np
    x = np.asarray(Fr, dtype=float) ** 2
    y = np.asarray(ratio, dtype=float) - 1.0
    if x.size < 1 or x.shape != y.shape or not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("Fr, ratio: need one or more finite pairs of the same length (got %d and %d values)"
                         % (np.size(Fr), np.size(ratio)))
    if not np.any(x > 0):
        raise ValueError("Fr: all zero; Eq 21 cannot be fitted")
    slope = float((x * y).sum() / (x * x).sum())
    rms = float(np.sqrt(np.mean((y - slope * x) ** 2)))
    return {"alphaF": 0.5 * slope * k, "k": k, "slope": slope, "rms": rms, "n": int(x.size)}


def linearFit(x, y):
    """Least-squares line y = slope x + intercept with Pearson's correlation coefficient r,
    as the paper's regressions of S_b/L0 against Fr and Fr1 (§5.5, Fig 19). Needs two or
    more finite pairs and x not all equal. Returns dict(slope, intercept, r, n)."""
    import numpy as np
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape != y.shape or x.size < 2 or not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("x, y: need two or more finite pairs of the same length (got %d and %d values)"
                         % (x.size, y.size))
    dx, dy = x - x.mean(), y - y.mean()
    sxx, syy = float((dx * dx).sum()), float((dy * dy).sum())
    if sxx == 0:
        raise ValueError("x: all values equal (%g); no line can be fitted" % x[0])
    slope = float((dx * dy).sum() / sxx)
    r = float((dx * dy).sum() / np.sqrt(sxx * syy)) if syy > 0 else 0.0
    return {"slope": slope, "intercept": float(y.mean() - slope * x.mean()), "r": r, "n": int(x.size)}


def submersion(hf, hb):
    """The block's state in the paper's §5 classification: ``"complete"`` when the free-flow
    depth at its station exceeds its height (h_f > h_b), else ``"partial"``."""
    return "complete" if hf > hb else "partial"


def flowAtStation(particles, x, halfWidth, bedZ=0.0, minPoints=4):
    """Depth and velocity of the flow at a station of a flume (coordinates along the flume:
    x downstream, z normal to the bed), from an MPM particle snapshot (``MpmEngine.particles()``).

    Uses the material points with |x_p − x| ≤ halfWidth [m]: depth h_f = highest point − bedZ
    [m] (the free surface; add half a particle spacing for the surface of the material), velocity
    v_f = their mass-weighted mean downstream velocity [m/s]. Returns (h_f, v_f), or (0, 0) with
    fewer than ``minPoints`` points at the station (the front has not arrived)."""
    import numpy as np
    sel = np.abs(particles["x"][:, 0] - x) <= halfWidth
    if sel.sum() < minPoints:
        return 0.0, 0.0
    m = particles["mass"][sel]
    h = float(particles["x"][sel, 2].max() - bedZ)
    v = float((m * particles["v"][sel, 0]).sum() / m.sum())
    return h, v


def frontProfile(particles, cell, bedZ=0.0, behind=(0.02, 0.05), minPoints=4):
    """The shape of a flow's front from an MPM particle snapshot (flume coordinates: x
    downstream, z normal to the bed): ``tip``, the x of the ``minPoints``-th most downstream
    point (a few points thrown ahead do not move it) [m]; ``tipHeight``, the mean height above
    ``bedZ`` of those ``minPoints`` most downstream points [m] (where the front's leading edge
    runs); ``nose``, the height above ``bedZ`` of the lowest point within one ``cell`` behind the
    tip [m] (a point resting on the bed sits its contact radius above it, so a front whose bed
    layer keeps up with its tip has a nose of about that);
    ``depth``, the height of the highest point within half a cell of each distance in
    ``behind`` upstream of the tip [m] (0 where there is none). ValueError with fewer than
    ``minPoints`` points."""
    import numpy as np
    x = np.asarray(particles["x"], dtype=float)
    if not (cell > 0 and len(x) >= minPoints):
        raise ValueError("frontProfile: needs cell > 0 (got %r) and at least %d points (got %d)"
                         % (cell, minPoints, len(x)))
    lead = np.argsort(x[:, 0], kind="stable")[-minPoints:]  # ties: the later points, reproducibly
    tip = float(x[lead, 0].min())
    nose = float(x[x[:, 0] >= tip - cell, 2].min() - bedZ)
    depth = []
    for d in behind:
        sel = np.abs(x[:, 0] - (tip - d)) <= cell / 2
        depth.append(float(x[sel, 2].max() - bedZ) if sel.any() else 0.0)
    return {"tip": tip, "tipHeight": float(x[lead, 2].mean() - bedZ), "nose": nose, "depth": depth}


class FlowProbe:
    """Free-flow calibration (paper §3.2.3, §5): records h_f and v_f at a station of a flume
    every call while the scene runs without the block, and reports them at the front's
    arrival, with the Froude numbers Fr = v_f/√(g h_f) and Fr1 = v_f/√(g L0).

    :param x: station (the block's upstream face) [m]; :param halfWidth: averaging half-width
        along x [m] (one or two cells); :param bedZ: bed surface [m]; :param L0: distance from
        the source to the station [m] (for Fr1); :param g: gravity magnitude [m/s²];
        :param window: time after the front's arrival over which v_f and h_f are averaged [s].
    """

    def __init__(self, x, halfWidth, bedZ=0.0, L0=None, g=G, window=0.05):
        self.x, self.halfWidth, self.bedZ, self.L0, self.g, self.window = x, halfWidth, bedZ, L0, g, window
        self.records = []  # (t, h_f, v_f)

    def sample(self, t, particles):
        h, v = flowAtStation(particles, self.x, self.halfWidth, self.bedZ)
        self.records.append((float(t), h, v))

    @property
    def arrival(self):
        """Time the front reached the station [s], or None."""
        for t, h, v in self.records:
            if h > 0:
                return t
        return None

    def result(self):
        """dict(arrival [s], h_f [m], v_f [m/s], Fr, Fr1): means over ``window`` after arrival."""
        t0 = self.arrival
        if t0 is None:
            raise ValueError("FlowProbe at x = %g m: the front never reached the station (run longer)" % self.x)
        rows = [(h, v) for t, h, v in self.records if t0 <= t <= t0 + self.window and h > 0]
        h = sum(r[0] for r in rows) / len(rows)
        v = sum(r[1] for r in rows) / len(rows)
        out = {"arrival": t0, "h_f": h, "v_f": v, "Fr": froude(v, h, self.g)}
        if self.L0:
            out["Fr1"] = froudeDistance(v, self.L0, self.g)
        return out


def runningMean(t, f, window):
    """The series f(t) averaged over ``window`` [s]: a centred running mean over
    round(window/Δt) samples (at least one), Δt the median sample interval (contact forces of
    single points are spiky)."""
    import numpy as np
    t, f = np.asarray(t, dtype=float), np.asarray(f, dtype=float)
    w = max(1, int(round(window / np.median(np.diff(t))))) if len(t) > 1 else 1
    return np.convolve(f, np.ones(w) / w, mode="same")


def intervalMean(t, impulse):
    """The mean force over each interval between records, from the impulse the records carry
    (coupled.h5's ``flow_impulse``, summed over every step since the run's start): at record i
    (impulse_i − impulse_{i−1}) / (t_i − t_{i−1}) [N], NaN at the first record. Unlike a record's
    own force (one step's, and a contact force swings from step to step) it holds every step."""
    import numpy as np
    t, j = np.asarray(t, dtype=float), np.asarray(impulse, dtype=float)
    out = np.full(j.shape, np.nan)
    if len(t) > 1:
        dt = np.diff(t)
        if not np.all(dt > 0):
            raise ValueError("t: the record times must increase")
        out[1:] = np.diff(j, axis=0) / (dt if j.ndim == 1 else dt[:, None])
    return out


def windowMean(t, impulse, window):
    """The mean force over a window of ``window`` [s] centred on each record, from the impulse
    summed since the run's start (coupled.h5's ``flow_impulse``): (J(t + w/2) − J(t − w/2)) / w,
    J interpolated linearly between records (exact where the window's ends fall on records);
    NaN where the window reaches past the first or last record."""
    import numpy as np
    t, j = np.asarray(t, dtype=float), np.asarray(impulse, dtype=float)
    if not window > 0:
        raise ValueError("window = %r: must be > 0 s" % (window,))
    a, b = t - 0.5 * window, t + 0.5 * window
    slack = 1e-9 * max(window, 1e-300)
    inside = (a >= t[0] - slack) & (b <= t[-1] + slack)
    out = (np.interp(np.clip(b, t[0], t[-1]), t, j) - np.interp(np.clip(a, t[0], t[-1]), t, j)) / window
    return np.where(inside, out, np.nan)


def impulseMean(t, impulse, start, end):
    """The mean force between times ``start`` and ``end`` [s] from the impulse summed since the
    run's start (coupled.h5's ``flow_impulse``): (J(end) − J(start)) / (end − start) [N], J
    interpolated linearly between records. Unlike the mean of the records' own forces (one
    step's each) it holds every step of the interval."""
    import numpy as np
    t, j = np.asarray(t, dtype=float), np.asarray(impulse, dtype=float)
    if not end > start:
        raise ValueError("end = %r: must be > start = %r s" % (end, start))
    slack = 1e-9 * (end - start)
    if len(t) < 2 or start < t[0] - slack or end > t[-1] + slack:
        raise ValueError("[%r, %r] s: must lie within the records, [%r, %r] s" % (
            start, end, t[0] if len(t) else None, t[-1] if len(t) else None))
    return float((np.interp(end, t, j) - np.interp(start, t, j)) / (end - start))


# A blow by parts: the spans after the first touch [s] whose mean forces :func:`blowParts` gives.
# The first 5 ms are the contact's onset, which the grid resolves last; after them the load the
# flow keeps up (docs/coupled-results.md, "The impact under grid refinement").
BLOW_PARTS = ((0.0, 0.002), (0.002, 0.005), (0.005, 0.025))


def blowPartName(span, kind="load"):
    """The key of a span of :data:`BLOW_PARTS` [s]: "load_0_2ms" for (0, 0.002) (:func:`blowParts`),
    "action_0_2ms" with ``kind`` "action" (:func:`blowLineOfAction`)."""
    return "%s_%g_%gms" % (kind, 1e3 * span[0], 1e3 * span[1])


def firstTouch(t, force):
    """When the flow first touched a block, as its records tell: the time [s] of the first record
    ``t`` whose flow force ``force`` is not zero (a record holds the step before it, so the
    contact began within the record interval before), or None where no record has one (the flow
    never came). :func:`touchTime` reads the step itself where the series has it."""
    import numpy as np
    touched = np.nonzero(np.abs(np.asarray(force, dtype=float)) > 0)[0]
    return float(np.asarray(t, dtype=float)[touched[0]]) if len(touched) else None


def firstContact(series):
    """The step the flow first touched a block in, from a block's series: the start [s] of the
    first step whose flow force on it was not zero (``series["first_contact"]``, which coupled.h5
    and :meth:`Flume.series` record), or None where the series does not hold one (not touched,
    or written before it was recorded)."""
    import numpy as np
    known = np.asarray(series.get("first_contact", []), dtype=float)
    known = known[np.isfinite(known)]
    return float(known[-1]) if len(known) else None


def touchTime(series):
    """When the flow first touched a block [s]: :func:`firstContact` where the series holds it
    (to the step), else :func:`firstTouch` of its records (to the record interval); None where
    the flow never came."""
    exact = firstContact(series)
    return exact if exact is not None else firstTouch(series["t"], series["Ft"])


def touchImpulse(series, key="J"):
    """(touch, t, impulse): the first touch (:func:`touchTime`) and a block's record times and
    one of its impulses since the run's start (``series[key]``: "J" the downstream impulse,
    "Ly" the angular impulse about the cross-slope axis), with a record added at the contact's
    first step where the series holds it between records: the impulse there is the one before it
    (no force came before), so a mean from the touch on (:func:`impulseMean`) counts from that
    step, not from an interpolation over the record interval that holds it. touch None where the
    flow never came."""
    touch, t, (j,) = touchImpulses(series, (key,))
    return touch, t, j


def touchImpulses(series, keys):
    """:func:`touchImpulse` of several impulses at once: (touch, t, [impulse of each key])."""
    import numpy as np
    t = np.asarray(series["t"], dtype=float)
    impulses = [np.asarray(series[key], dtype=float) for key in keys]
    touch, exact = touchTime(series), firstContact(series)
    if exact is not None and not np.any(np.isclose(t, exact, rtol=0, atol=1e-12)):
        k = int(np.searchsorted(t, exact))  # records before it hold the impulse before any contact
        t = np.insert(t, k, exact)
        impulses = [np.insert(j, k, j[k - 1] if k > 0 else 0.0) for j in impulses]
    return touch, t, impulses


def blowParts(series, spans=BLOW_PARTS):
    """The mean force over each span after the first touch, from the impulse summed since the
    run's start (:func:`touchImpulse`; :func:`impulseMean`): {"load_0_2ms": ..., "load_2_5ms":
    ..., "load_5_25ms": ...} [N]; a span the records do not reach is left out; {} where the flow
    never came. Where the series holds the first contact the spans count from its step, else from
    the first record with a force."""
    touch, t, j = touchImpulse(series)
    if touch is None:
        return {}
    return {blowPartName((a, b)): impulseMean(t, j, touch + a, touch + b)
            for a, b in spans if touch + b <= t[-1]}


def blowLineOfAction(series, spans=BLOW_PARTS):
    """Where the blow acts: for each span after the first touch (as :func:`blowParts`), the height
    [m] above the block's centroid at which the line of action of the flow's mean force (in the
    plane of the flume's axis and the bed's normal) crosses the vertical through the centroid:
    the angular impulse about the cross-slope axis over the span divided by the downstream
    impulse over it (``series["Ly"]``, ``series["J"]``: T_y / F_x of their means, the height at
    which a downstream push alone would turn the block as the flow did; a push on the top face
    downstream of the centroid turns it the same way and raises it, above the top where that
    push is large); NaN over a span without a downstream impulse. {"action_0_2ms": ...}; {} where
    the flow never came or the series has no angular impulse (files written before it was
    recorded)."""
    if "Ly" not in series:
        return {}
    touch, t, (j, ly) = touchImpulses(series, ("J", "Ly"))
    if touch is None:
        return {}
    out = {}
    for a, b in spans:
        if touch + b <= t[-1]:
            push = impulseMean(t, j, touch + a, touch + b)
            out[blowPartName((a, b), "action")] = impulseMean(t, ly, touch + a, touch + b) / push if push else math.nan
    return out


def forceSource(series):
    """Where :func:`meanForce` and :func:`meanForceBetween` read a block's force from: "impulse"
    where the series records one (``series["J"]``, every step's force), else "records" (files
    written before the impulse was recorded: the records' own forces ``series["Ft"]``, one
    step's each, noisier: a contact force swings from step to step)."""
    import numpy as np
    return "impulse" if "J" in series and np.isfinite(series["J"]).any() else "records"


def meanForce(series, window):
    """A block's downstream flow force averaged over ``window`` [s] centred on each record [N]:
    :func:`windowMean` of its impulse, or :func:`runningMean` of its records' forces
    (:func:`forceSource`). ``series``: a dict of :meth:`mpmsdem.flume.Flume.series` or
    :func:`driverBlockSeries`."""
    if forceSource(series) == "impulse":
        return windowMean(series["t"], series["J"], window)
    return runningMean(series["t"], series["Ft"], window)


def meanForceBetween(series, start, end):
    """A block's mean downstream flow force between ``start`` and ``end`` [s] [N]:
    :func:`impulseMean` of its impulse, or the mean of its records' forces in [start, end]
    (:func:`forceSource`)."""
    import numpy as np
    if forceSource(series) == "impulse":
        return impulseMean(series["t"], series["J"], start, end)
    t = np.asarray(series["t"])
    inside = (t >= start) & (t <= end)
    if not inside.any():
        raise ValueError("[%r, %r] s: no record there" % (start, end))
    return float(np.asarray(series["Ft"])[inside].mean())


def peakWindowMean(t, impulse, window):
    """The largest mean force over any window of ``window`` [s] within the records, from the
    impulse summed since the run's start, and the window's centre: (peak [N], t_centre [s]). J is
    linear between records, so the mean is linear in the window's position between the positions
    where one of its ends meets a record, and the largest lies at one of those: every window
    starting or ending on a record is tried (a window centred on records only would miss a short
    blow's peak by up to half a record interval)."""
    import numpy as np
    t, j = np.asarray(t, dtype=float), np.asarray(impulse, dtype=float)
    if not window > 0:
        raise ValueError("window = %r: must be > 0 s" % (window,))
    slack = 1e-9 * window
    starts = np.concatenate([t, t - window])
    starts = starts[(starts >= t[0] - slack) & (starts + window <= t[-1] + slack)]
    if not len(starts):
        raise ValueError("window = %r s: longer than the records (%r to %r s)" % (window, float(t[0]), float(t[-1])))
    starts = np.clip(starts, t[0], t[-1] - window)
    means = (np.interp(starts + window, t, j) - np.interp(starts, t, j)) / window
    k = int(np.nanargmax(means))
    return float(means[k]), float(starts[k] + 0.5 * window)


def peakMeanForce(series, window):
    """A block's largest downstream flow force over ``window`` [s] and the window's centre: (peak
    [N], t_peak [s]). From the impulse (:func:`peakWindowMean`: any window within the records) or,
    without one (:func:`forceSource`), the largest running mean of the records' forces."""
    if forceSource(series) == "impulse":
        return peakWindowMean(series["t"], series["J"], window)
    return smoothedPeak(series["t"], series["Ft"], window)


def smoothedPeak(t, f, smooth=None):
    """Largest value of the series f(t) and its time: (peak, t_peak). With ``smooth`` [s] the
    series is first averaged over that window (:func:`runningMean`)."""
    import numpy as np
    t, f = np.asarray(t, dtype=float), np.asarray(f, dtype=float)
    if smooth:
        f = runningMean(t, f, smooth)
    j = int(np.argmax(f))
    return float(f[j]), float(t[j])


# When a block counts as at rest in docs/ and the examples' summaries: no point of it faster than
# REST_SPEED [m/s] from then on to the end of the record (its centre's speed plus its turn rate
# times its circumradius bound every point's speed).
REST_SPEED = 0.01


def restTime(t, speed, rotation=None, radius=0.0, speedBelow=REST_SPEED):
    """The time [s] from which a block stays at rest to the end of its record: the bound
    ``speed`` + ω ``radius`` on the speed of its points stays below ``speedBelow`` [m/s] at every
    record from then on. ``speed``: its centre's [m/s]; ω: the rate of ``rotation`` (the whole
    angle turned [deg], as :func:`driverBlockSeries` gives it) over the interval before and the
    one after the record [rad/s], 0 without it; ``radius``: the farthest point of the block from
    its centre [m]. None when the last record is not at rest: the run ended before the block
    stopped. ValueError naming the argument for a bound ≤ 0, a negative radius, or series of
    different lengths."""
    import numpy as np
    t, speed = np.asarray(t, dtype=float), np.asarray(speed, dtype=float)
    if not (speedBelow > 0 and math.isfinite(speedBelow)):
        raise ValueError("speedBelow = %r m/s: must be finite and > 0" % (speedBelow,))
    if not (radius >= 0 and math.isfinite(radius)):
        raise ValueError("radius = %r m: must be finite and >= 0" % (radius,))
    if t.ndim != 1 or speed.shape != t.shape or len(t) < 2:
        raise ValueError("t and speed: one value per record, at least two records (got %s and %s)"
                         % (t.shape, speed.shape))
    bound = speed.copy()
    if rotation is not None:
        rotation = np.asarray(rotation, dtype=float)
        if rotation.shape != t.shape:
            raise ValueError("rotation: one value per record (got %s for %s)" % (rotation.shape, t.shape))
        omega = np.radians(np.abs(np.diff(rotation))) / np.diff(t)
        turning = np.zeros(len(t))
        turning[1:] = omega
        turning[:-1] = np.maximum(turning[:-1], omega)
        bound += turning * radius
    moving = ~(bound < speedBelow)
    if moving[-1]:
        return None
    last = np.nonzero(moving)[0]
    return float(t[0] if len(last) == 0 else t[last[-1] + 1])


def driverBlockSeries(folder, block=None, initial=True):
    """A block's series from the coupled.h5 that ``mpmsdem-run`` or a YADE ``CoupledEngine(output=
    folder)`` wrote in ``folder``, with the
    keys of :meth:`mpmsdem.flume.Flume.series` (x downstream): t, travel (S_b), vx, speed (of its
    centre) [m/s], Ft, Ff, Fe
    (downstream flow force of the step before each record: total, on faces, on edges) [N], J
    (the downstream impulse since the run's start [N s]), Ly (the angular impulse about the
    centroid and the cross-slope axis y since the start [N m s]) and Fmean (the mean downstream
    force since the record before, :func:`intervalMean`; these where the file records impulses),
    first_contact (when the flow first touched it, as known at each record, NaN before; where the
    file records it: :func:`touchTime`) [s], rotation (the whole angle turned
    since the scene's start), tilt and yaw [deg], and the scene's flow_kinetic, flow_potential and
    block_kinetic [J], and flow_front [m] (the flow's most downstream point, from the mpm.h5
    beside it where there is one). ``block``: its index in the file (default: the first
    block that moves; a flume's bed is fixed). ``initial``: keep the driver's record at the
    start; False leaves it out, as :meth:`Flume.series` has no record before the first step
    (travel still counts from the start). Returns (series, scene dict; None from a
    CoupledEngine, whose file holds no scene). Needs h5py only, not YADE: runs made on another
    machine are read here."""
    import json
    import os
    import h5py
    import numpy as np
    path = os.path.join(folder, "coupled.h5")
    if not os.path.exists(path):
        raise ValueError("%s: no coupled.h5 there (the output folder of a coupled mpmsdem-run or CoupledEngine)"
                         % folder)
    with h5py.File(path, "r", locking=False) as f:  # without HDF5's file lock, as the writers: a live run reads
        g = f["series"]
        t = g["time"][:]
        pos, vel = g["pos"][:], g["vel"][:]
        if block is None:
            moving = [k for k in range(pos.shape[1] // 3) if np.ptp(pos[:, 3 * k:3 * k + 3], axis=0).max() > 0]
            if not moving:
                raise ValueError("%s: no block moved in coupled.h5" % folder)
            block = moving[0]
        if not 0 <= block < pos.shape[1] // 3:
            raise ValueError("block = %r: must be in [0, %d) (the blocks of %s)" % (block, pos.shape[1] // 3, path))
        c = slice(3 * block, 3 * block + 3)
        # from the scene's start: a run started from another's flow records from later on
        x0 = json.loads(f.attrs["start_positions"])[block][0] if "start_positions" in f.attrs else pos[0, c][0]
        s = {"t": t, "travel": pos[:, c][:, 0] - x0, "vx": vel[:, c][:, 0], "speed": np.linalg.norm(vel[:, c], axis=1),
             "Ft": g["flow_force"][:, c][:, 0], "Ff": g["face_force"][:, c][:, 0], "Fe": g["edge_force"][:, c][:, 0],
             "rotation": np.degrees(np.linalg.norm(g["rotation"][:, c], axis=1))}
        if "flow_impulse" in g:  # files written before the impulse was recorded have none
            s["J"] = g["flow_impulse"][:, c][:, 0]
            s["Ly"] = g["flow_angular_impulse"][:, c][:, 1]
            s["Fmean"] = intervalMean(t, s["J"])
        if "flow_first_contact" in g:  # nor before the first contact was
            s["first_contact"] = g["flow_first_contact"][:, block]
        turns = np.array([tiltAndYaw(np.linalg.norm(r), r) for r in g["rotation"][:, c]]).reshape(-1, 2)
        s["tilt"], s["yaw"] = turns[:, 0], turns[:, 1]
        for k in ("flow_kinetic", "flow_potential", "block_kinetic"):
            if k in g:  # the driver and CoupledEngine write them; other writers may not
                s[k] = g[k][:]
        scene = json.loads(f.attrs["parameters"]) if "parameters" in f.attrs else None  # the driver's scene
    flow = os.path.join(folder, "mpm.h5")
    if os.path.exists(flow):
        with h5py.File(flow, "r", locking=False) as f:
            s["flow_front"] = np.interp(t, f["series/time"][:], f["series/front_x"][:])
    if not initial:
        s = {k: v[1:] for k, v in s.items()}
    return s, scene


def stateIsFinite(state):
    """Whether a YADE body state's position, velocity, angular velocity and orientation are all
    finite numbers."""
    return all(math.isfinite(v) for vec in (state.pos, state.vel, state.angVel) for v in vec) and \
        all(math.isfinite(state.ori[k]) for k in range(4))


def referenceCheckArguments(doc):
    """The command line of a check against stored reference numbers: ``--regenerate`` (store
    this run's numbers as the new reference); ``doc``: the check's description (--help)."""
    import argparse
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--regenerate", action="store_true", help="store this run's numbers as the new reference")
    return ap.parse_args()


def finishCheck(failures):
    """End a check: exit status 1 with "FAILED: ..." on stderr when ``failures`` (messages)
    is not empty, else print "OK"."""
    import sys
    if failures:
        print("FAILED: " + "; ".join(failures), file=sys.stderr)
        sys.exit(1)
    print("OK")


def runFlumeCheck(scene, duration, sampleEvery=0.002):
    """Run a check's flume scene (:class:`mpmsdem.flume.Flume` with one cube) for ``duration``
    [s], sampled every ``sampleEvery`` [s]. Returns (the cube's series, the numbers every flume
    check looks at: ``mass_error`` [kg], ``finite``, ``max_yaw`` [deg], ``particles``,
    ``flip_blend``), for :func:`flumeCheckFailures`."""
    import math
    import numpy as np
    from yade import O
    m0 = float(scene.mpm.particles()["mass"].sum())
    scene.run(duration, sampleEvery=sampleEvery)
    s = scene.series(0)
    state = O.bodies[scene.blockIds[0]].state
    return s, {"mass_error": abs(float(scene.mpm.particles()["mass"].sum()) - m0),
               "finite": all(math.isfinite(v) for v in state.pos), "max_yaw": float(np.abs(s["yaw"]).max()),
               "particles": scene.mpm.numParticles, "flip_blend": scene.flipBlend()}


def flumeCheckFailures(r, symmetric=True):
    """What every flume check refuses in its result dict ``r``, as messages: a change of the
    flow's mass (``mass_error`` [kg]: a material point method conserves it exactly), a cube
    whose state is not finite (``finite``), and a cube (``max_yaw`` [deg]) turning on the bed in a scene ``symmetric`` about its centre line (beyond 1e-6°)."""
    failures = []
    if r["mass_error"] != 0:
        failures.append("flow mass changed by %g kg" % r["mass_error"])
    if not r["finite"]:
        failures.append("the cube's state is not finite")
    if symmetric and not r["max_yaw"] < 1e-6:
        failures.append("the cube turned %.3g deg on the bed in a scene symmetric about its centre line" % r["max_yaw"])
    return failures


def checkAgainstReference(values, path, tolerances, regenerate=False, stored=None):
    """Regression check of a scene's numbers against a stored reference (JSON), the way the
    project's checks and a user's regression scripts use it.

    :param values: dict of this run's numbers; :param path: the reference JSON file;
    :param tolerances: {key: relative tolerance} of the keys compared (two-sided);
    :param regenerate: store ``values`` (the keys in ``stored``, default those of
        ``tolerances``) as the new reference instead of comparing.
    Prints one line per compared key; returns the list of drift messages (empty: all within).
    """
    import json
    import os
    if regenerate:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        with open(path, "w") as f:
            json.dump({k: values[k] for k in (stored or tolerances)}, f, indent=1)
        print("reference written: %s" % path)
        return []
    with open(path) as f:
        ref = json.load(f)
    width = max(len(k) for k in tolerances)
    failures = []
    for key, tol in tolerances.items():
        rel = abs(values[key] - ref[key]) / abs(ref[key])
        print("  %-*s %.4f (reference %.4f, %+.1f %%, tolerance %.0f %%) %s"
              % (width, key, values[key], ref[key], 100 * (values[key] / ref[key] - 1), 100 * tol,
                 "ok" if rel <= tol else "DRIFT"))
        if rel > tol:
            failures.append("%s = %.4f drifted %.1f %% from the reference %.4f (tolerance %.0f %%)"
                            % (key, values[key], 100 * rel, ref[key], 100 * tol))
    return failures
