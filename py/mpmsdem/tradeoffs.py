"""Which settings give which error at which cost: the measured trade-offs of docs/tradeoffs.md.

    from mpmsdem import tradeoffs
    p = tradeoffs.propose(0.05, output="runout")   # cheapest measured setting within 5 %
    print(p)                                        # its settings, measured error and cost
    for row in tradeoffs.table("runout"):           # every measured setting for that output
        print(row)
    tradeoffs.nearest("flow_depth", cells_per_block_height=2)      # the error measured nearest a setting
    tradeoffs.propose(1.0, output="peak_force")     # a wall's first blow, in cells per flow depth
    tradeoffs.propose(0.3, output="block_peak_force")   # the §3.2 cube's, in cells per block height
    tradeoffs.propose(0.1, output="glued_block_peak_force")  # a glued 20 or 40 mm cube's, in cells per block height
    tradeoffs.nearest("glued_block_peak_force", block_height=0.02, cells_per_block_height=5)  # the 20 mm cube's

The numbers are measurements, shipped with the package in ``tradeoffs.json`` and written by the
scripts that made them (``scripts/bench/tradeoff_mpm.py``,
``scripts/bench/tradeoff_stacked_blocks.py``, ``scripts/validation/flume_convergence.py`` and
``scripts/validation/impact_walls.py``, with ``--package-data``): each study
ran one scene at many settings, took the finest setting as the converged reference and
recorded every output's relative error against it and the run's cost relative to the default
setting (the work, points x steps, and the CPU time of one thread, all runs in one command).
A study refined towards a limit it could not run (the §3.2 cube's impact at 1 to 5 cells per
block height; a rigid wall struck by the flume's flow at 2.4, 4.2 and 7.9 cells per flow depth)
takes the limit extrapolated through its three finest spacings as the reference
(``extrapolated``: how) and lists the outputs whose sequence gave no limit under
``unconverged``. Asking for an unconverged output raises a ValueError that says what was
measured, or, where another study's converged, the proposal carries the others' findings in
``caveats`` (:func:`unconverged` lists them). Proposals come
from the resolution settings (grid spacing, points per cell, precision); rows that change a
model choice such as the FLIP/PIC alpha are listed by :func:`table` with ``sensitivity`` set,
and not proposed. A proposal is therefore an empirical guide for scenes like the measured one
(their scene, commit and command come with it), not a bound: check a proposal on your own scene
once against a finer run.
"""
import json
import os

_DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "tradeoffs.json")


class Proposal:
    """A measured setting: ``settings`` (dict), ``error`` (signed relative error of ``output``
    against the study's reference), ``cost`` (work relative to the study's default setting;
    ``cpuCost``: CPU time relative to it, None where the runs shared the machine), ``reference`` /
    ``sensitivity`` flags, and where it
    was measured (``study``: name, scene, commit, machine, command, reference settings). The
    FLIP/PIC blend each row's flow ran with is one of its settings: ``settings["flip_viscosity"]``,
    a PIC viscosity [m²/s] (docs/physics.md, "The blend as a viscosity")."""

    def __init__(self, output, row, study, caveats=()):
        self.output = output
        self.settings = dict(row["settings"])
        self.error = row["errors"][output]
        self.cost = row["cost"]
        self.cpuCost = row.get("cpu_cost")
        self.reference = bool(row.get("reference", False))
        self.sensitivity = bool(row.get("sensitivity", False))
        self.study = {k: study[k] for k in ("name", "scene", "commit", "machine", "command", "reference")}
        # what other studies found of the same output without a limit (e.g. a wall's peak force
        # converges where a block's did not): a proposal holds only for scenes like its own
        self.caveats = list(caveats)

    def __repr__(self):
        return "Proposal(%s: %s, error %+.2f %%, cost %.3g x default; measured on %s, commit %s%s)" % (
            self.output, ", ".join("%s=%s" % kv for kv in sorted(self.settings.items())), 100 * self.error,
            self.cost, self.study["scene"], self.study["commit"],
            "".join("; not converged elsewhere: " + c for c in self.caveats))


def _studies(path=None):
    with open(path or _DATA) as f:
        data = json.load(f)
    return data["studies"]


def _outputsOf(studies):
    return sorted({o for s in studies for r in s["rows"] for o in r["errors"]})


def outputs(path=None):
    """The outputs with measured errors, e.g. ``['deposit_height', 'runout']``."""
    return _outputsOf(_studies(path))


def _unconverged(studies, output):
    """What the studies that measured ``output`` without a converged value say of it."""
    return ["%s (study %s, commit %s)" % (s["unconverged"][output], s["name"], s["commit"])
            for s in studies if output in s.get("unconverged", {})]


def unconverged(output, path=None):
    """What each study that refined ``output`` without reaching a limit measured of it (a list
    of sentences, empty when every study that measured it converged), e.g. the §3.2 cube's
    first blow at 1, 2 and 2.8 cells per block height."""
    return _unconverged(_studies(path), output)


def table(output, path=None):
    """Every measured setting for ``output``, cheapest first: a list of :class:`Proposal`.
    An output a study refined without reaching a converged value (its sequence not monotone)
    has no errors to offer: a ValueError says what was measured when no other study converged
    in it, and otherwise each row carries it in ``caveats``."""
    studies = _studies(path)
    known = _outputsOf(studies)
    if output not in known:
        why = _unconverged(studies, output)
        if why:
            raise ValueError("output = %r: measured under refinement but not converged, so no setting's error is "
                             "known: %s" % (output, "; ".join(why)))
        raise ValueError("output = %r: not measured; one of %s" % (output, ", ".join(known)))
    why = _unconverged(studies, output)
    rows = [Proposal(output, r, s, why) for s in studies for r in s["rows"] if output in r["errors"]]
    return sorted(rows, key=lambda p: (p.cost, p.cpuCost if p.cpuCost is not None else p.cost, abs(p.error)))


def propose(error, output="runout", maxCost=None, path=None):
    """The cheapest measured setting whose |relative error| in ``output`` is at most ``error``.

    :param error: target relative error, > 0 (0.05: within 5 % of the converged reference).
    :param output: a measured output (see :func:`outputs`).
    :param maxCost: optional cost limit relative to the default setting, > 0.
    :raises ValueError: bad arguments, or no measured setting meets the target (the message
        gives the smallest error measured and at what cost).
    """
    if not (isinstance(error, (int, float)) and error > 0):
        raise ValueError("error = %r: must be a relative error > 0 (e.g. 0.05 for 5 %%)" % (error,))
    if maxCost is not None and not (isinstance(maxCost, (int, float)) and maxCost > 0):
        raise ValueError("maxCost = %r: must be > 0 (cost relative to the default setting) or None" % (maxCost,))
    rows = table(output, path)
    # a reference's error is 0 by construction, not measured; a sensitivity row changes a model
    # choice (e.g. the FLIP/PIC alpha), whose agreement with the reference can be a coincidence
    # of two errors: neither is proposed
    rows = [p for p in rows if not (p.reference or p.sensitivity)]
    fit = [p for p in rows if abs(p.error) <= error and (maxCost is None or p.cost <= maxCost)]
    if fit:
        return fit[0]
    best = min(rows, key=lambda p: abs(p.error))
    within = [p for p in rows if maxCost is None or p.cost <= maxCost]
    msg = "error = %g: no measured setting of %s is within it" % (error, output)
    if maxCost is not None and within:
        closest = min(within, key=lambda p: abs(p.error))
        msg += " at cost <= %g (closest there: %+.2f %% at %.3g x, %s)" % (
            maxCost, 100 * closest.error, closest.cost, closest.settings)
    msg += ("; the smallest measured error is %+.2f %% at %.3g x the default cost (%s); below that only the "
            "study's reference (%s) is left, whose own error was not measured") % (
        100 * best.error, best.cost, best.settings, best.study["reference"])
    raise ValueError(msg)


def nearest(output, path=None, **settings):
    """The measured row of ``output`` whose settings are nearest to ``settings`` (e.g.
    ``cells_per_block_height=2``; each compared by its ratio, rows without one of them left
    out): a :class:`Proposal`, whose ``error`` is the error measured there. Raises ValueError as
    :func:`table` does, and when no row has the settings named."""
    import math
    if not settings or not all(isinstance(v, (int, float)) and 0 < v < math.inf for v in settings.values()):
        raise ValueError("settings = %r: name one or more measured settings, each a number > 0" % (settings,))
    rows = [p for p in table(output, path) if not p.reference and all(k in p.settings for k in settings)]
    if not rows:
        why = unconverged(output, path)
        raise ValueError("settings %s: no measured row of %s has them%s" % (
            ", ".join(sorted(settings)), output, "".join("; not converged: " + w for w in why)))
    return min(rows, key=lambda p: sum(abs(math.log(p.settings[k] / v)) for k, v in settings.items()))
