"""Calibration of scene parameters against measurements (paper §3.2, Appendix C).

The paper fits the basal friction of the flow and its maximum dynamic friction μ₂ with a
genetic algorithm, minimising the misfit between simulated and measured block travel. This
module does the same with SciPy's differential evolution (an evolutionary algorithm of the
same family), every candidate a simulation in its own process (:mod:`mpmsdem.sweep`: local
processes or a Dask cluster), every finished candidate stored at once::

    from mpmsdem import calibrate
    fit = calibrate.calibrate("examples/calibrate_flume.py:flumeRun",
                              bounds={"basalFriction": (0.01, 0.5), "mu_2": (0.3, 0.8)},
                              targets={"travel": 0.085}, store="results/calib/runs.jsonl",
                              plot="results/calib/calibration.png")
    print(fit["params"], fit["loss"])

Resuming: run the same call again after an interruption. Differential evolution draws its
trial vectors from a seeded generator and from the losses of earlier ones; every loss it
asks for again comes from the store, so the search retraces its steps without running a
simulation and goes on from where it stopped, to the same optimum an uninterrupted search
reaches (with the same settings; other settings still reuse any identical candidate).

Loss (Appendix C's "discrepancy between simulated and measured" values): the weighted sum of
squared relative misfits, Σ_k w_k ((simulated_k − measured_k) / measured_k)².
"""
import math
import numbers

from . import sweep

# Appendix C's search ranges of the two calibrated parameters.
APPENDIX_C_BOUNDS = {"basalFriction": (0.01, 0.5), "mu_2": (0.3, 0.8)}


def loss(result, targets, weights=None):
    """Weighted sum of squared relative misfits of ``result`` (a task's dict) to ``targets``;
    RuntimeError when the result lacks a target quantity."""
    missing = [k for k in targets if k not in result]
    if missing:
        raise RuntimeError("the task's result has no %s (it returned %s): name targets after the quantities the task "
                           "returns" % (", ".join(repr(k) for k in missing), ", ".join(sorted(result))))
    w = weights or {}
    return sum(w.get(k, 1.0) * ((result[k] - t) / t) ** 2 for k, t in targets.items())


def _check(task, bounds, targets, fixed, weights, popsize, maxiter, threshold, tol, seed):
    if not isinstance(bounds, dict) or not bounds:
        raise ValueError("bounds = %r: give the fitted parameters as {name: (lower, upper)}, e.g. %r"
                         % (bounds, APPENDIX_C_BOUNDS))
    for name, b in bounds.items():
        ok = isinstance(b, (tuple, list)) and len(b) == 2 and all(
            isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) for v in b)
        if not ok:
            raise ValueError("bounds[%r] = %r: must be (lower, upper), two finite numbers" % (name, b))
        if not b[0] < b[1]:
            raise ValueError("bounds[%r] = %r: the lower bound must be < the upper bound" % (name, tuple(b)))
    if not isinstance(targets, dict) or not targets:
        raise ValueError("targets = %r: give at least one measured value the task returns, e.g. {\"travel\": 0.085} "
                         "(block travel distance [m]) or {\"runout\": 1.2} [m]" % (targets,))
    for name, t in targets.items():
        if not (isinstance(t, numbers.Real) and math.isfinite(t) and t != 0):
            raise ValueError("targets[%r] = %r: must be a finite non-zero number (the misfit is relative to it)"
                             % (name, t))
    for name, w in (weights or {}).items():
        if name not in targets:
            raise ValueError("weights[%r]: not a target (targets: %s)" % (name, ", ".join(targets)))
        if not (isinstance(w, numbers.Real) and math.isfinite(w) and w > 0):
            raise ValueError("weights[%r] = %r: must be a finite number > 0" % (name, w))
    both = set(bounds) & set(fixed)
    if both:
        raise ValueError("%s: both fitted (bounds) and fixed; give each parameter once" % ", ".join(sorted(both)))
    accepted = sweep.taskParameters(task)
    if accepted is not None:
        for what, names in (("bounds", bounds), ("fixed", fixed)):
            unknown = [n for n in names if n not in accepted]
            if unknown:
                raise ValueError("%s: unknown parameter %s of task %s; it accepts: %s"
                                 % (what, ", ".join(repr(n) for n in unknown), task, ", ".join(accepted)))
    for name, v, lo in (("popsize", popsize, 1), ("maxiter", maxiter, 0), ("seed", seed, 0)):
        if not (isinstance(v, numbers.Integral) and v >= lo):
            raise ValueError("%s = %r: must be an integer >= %d" % (name, v, lo))
    for name, v in (("threshold", threshold), ("tol", tol)):
        if not (isinstance(v, numbers.Real) and v >= 0):
            raise ValueError("%s = %r: must be a number >= 0" % (name, v))


def calibrate(task, bounds, targets, store, fixed=None, weights=None, popsize=8, maxiter=20, threshold=1e-4,
              tol=0.01, seed=1, polish=False, workers=1, scheduler=None, retries=2, timeout=None, threads=1,
              progress=True, plot=None):
    """Fit ``bounds``' parameters of ``task`` so that its results match ``targets``.

    :param task: ``"package.module:function"`` or ``"path/to/file.py:function"``: runs one
        simulation with the given keyword parameters and returns a dict of measured
        quantities (see :mod:`mpmsdem.sweep`).
    :param bounds: ``{name: (lower, upper)}`` of the fitted parameters, lower < upper, in the
        task's units (Appendix C: basal friction 0.01–0.5, μ₂ 0.3–0.8).
    :param targets: ``{quantity: measured value}``, finite and non-zero, e.g.
        ``{"travel": 0.085}`` [m]; the task's result must contain each quantity.
    :param store: JSON-lines results store [path]; re-running the call resumes from it.
    :param fixed: ``{name: value}`` passed unchanged to every run (default none).
    :param weights: ``{quantity: w > 0}`` of the loss (default 1 each).
    :param popsize: population = max(5, popsize × number of fitted parameters) candidates
        per generation (default 8).
    :param maxiter: generations after the initial population, >= 0 (default 20).
    :param threshold: stop once the best loss is at most this, >= 0 (default 1e-4: 1 %
        relative misfit of one target; Appendix C's "target threshold").
    :param tol: SciPy's relative convergence tolerance of the population's losses (0.01).
    :param seed: generator seed, integer >= 0 (default 1); a resumed search needs the same.
    :param polish: refine the best candidate with L-BFGS-B afterwards (default False: it
        runs candidates one by one, with finite differences of noisy simulations).
    :param workers, scheduler, retries, timeout, threads: as :class:`mpmsdem.sweep.Executor`
        (local processes at a time, default 1; a Dask scheduler address; extra attempts of a
        failed candidate, 2; limit of one candidate [s]; OMP_NUM_THREADS of a candidate, 1).
    :param progress: print one line per candidate and per generation (default True).
    :param plot: PNG path for :func:`plotCalibration`, or None (default).
    :returns: dict with ``params`` (best fitted values), ``loss``, ``result`` (the task's
        result at the best), ``evaluations`` (distinct candidates of this search),
        ``computed`` (simulations run in this call), ``reused`` (answered by the store),
        ``generations``, ``converged``, ``message``, ``store``.
    :raises ValueError: bad arguments (naming the parameter); :class:`mpmsdem.sweep.SweepError`
        when a candidate failed every attempt (the store keeps the finished ones).
    """
    import numpy as np
    from scipy.optimize import differential_evolution
    fixed = dict(fixed or {})
    task = sweep.normaliseTask(task)
    _check(task, bounds, targets, fixed, weights, popsize, maxiter, threshold, tol, seed)
    names = list(bounds)
    say = print if progress else (lambda text: None)
    state = {"best": math.inf, "bestParams": None, "bestResult": None, "keys": set(), "generation": 0}

    def describe(rec):
        v = loss(rec["result"], targets, weights)
        got = ", ".join("%s %.5g (target %.5g)" % (k, rec["result"][k], t) for k, t in targets.items())
        return "-> %s, loss %.3g" % (got, v)

    ex = sweep.Executor(task, store, workers=workers, scheduler=scheduler, retries=retries, timeout=timeout,
                        threads=threads, progress=progress, describe=describe)

    def evaluate(_func, vectors):
        cases = [dict(fixed, **{n: float(x) for n, x in zip(names, vec)}) for vec in vectors]
        records = ex.map(cases)
        bad = sweep.failed(records)
        if bad:
            raise sweep.SweepError("%d candidate(s) failed every attempt; the store %s keeps the finished ones, "
                                   "re-run to retry:\n%s" % (len(bad), ex.store.path, "\n".join(
                                       "  %s: %s" % (sweep.describeParams(r["params"]), r["error"]) for r in bad)))
        out = []
        for case, rec in zip(cases, records):
            v = loss(rec["result"], targets, weights)
            state["keys"].add(rec["key"])
            if v < state["best"]:
                state.update(best=v, bestParams={n: case[n] for n in names}, bestResult=rec["result"])
            out.append(v)
        return out

    def generation(xk, convergence=None):
        state["generation"] += 1
        say("generation %d: best loss %.4g at %s (%d candidates, %d simulated now, %d from the store)"
            % (state["generation"], state["best"], sweep.describeParams(state["bestParams"]), len(state["keys"]),
               ex.started - ex.failures, ex.reused))
        return state["best"] <= threshold

    try:
        res = differential_evolution(lambda x: evaluate(None, [x])[0], [tuple(bounds[n]) for n in names],
                                     workers=evaluate, updating="deferred", popsize=popsize, maxiter=maxiter, tol=tol,
                                     seed=seed, polish=polish, init="latinhypercube", callback=generation)
    finally:
        ex.close()
    converged = bool(state["best"] <= threshold or res.success)
    message = ("best loss %.3g <= threshold %.3g" % (state["best"], threshold) if state["best"] <= threshold
               else res.message)
    out = {"params": {n: float(v) for n, v in zip(names, np.atleast_1d(res.x))}, "loss": float(res.fun),
           "result": state["bestResult"], "evaluations": len(state["keys"]), "computed": ex.started - ex.failures,
           "reused": ex.reused, "generations": state["generation"], "converged": converged, "message": message,
           "store": ex.store.path}
    if out["loss"] > state["best"]:  # DE reports its population's best; a stopped search may hold a better one
        out.update(params=state["bestParams"], loss=state["best"])
    say("calibration: %s = %s, loss %.4g (%s); %d candidates, %d simulated in this call"
        % ("/".join(names), "/".join("%.6g" % out["params"][n] for n in names), out["loss"], message,
           out["evaluations"], out["computed"]))
    if plot:
        plotCalibration(ex.store.path, names, targets, plot, fixed=fixed, weights=weights)
    return out


def plotCalibration(store, names, targets, path, fixed=None, weights=None):
    """PNG of a calibration's store: the loss of every candidate in the order they were run,
    with the running best, and the loss over the plane of the first two fitted parameters
    (over the parameter's axis with one), the best marked. Works on a store that is still
    being written (e.g. to watch a long calibration).

    :param store: the calibration's JSON-lines store [path].
    :param names: the fitted parameters' names, as in ``bounds``.
    :param targets, weights: as :func:`calibrate` (the loss is recomputed from the results).
    :param path: the PNG to write; :param fixed: the fixed parameters of the calibration
        (records of other fixed values in the same store are left out).
    :returns: ``path``."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    fixed = fixed or {}
    rows, seen = [], set()
    for r in sweep.readStore(store):
        p = r["params"]
        if r["status"] != "ok" or r["key"] in seen or any(n not in p for n in names):
            continue
        if any(p.get(k) != v for k, v in sweep.canonicalParams(fixed).items()):
            continue
        seen.add(r["key"])
        rows.append([p[n] for n in names] + [loss(r["result"], targets, weights)])
    if not rows:
        raise ValueError("store %s: no finished candidate with parameters %s to plot" % (store, ", ".join(names)))
    a = np.array(rows)
    f = np.maximum(a[:, -1], 1e-300)
    best = int(np.argmin(f))
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    ax[0].semilogy(np.arange(1, len(f) + 1), f, "o", ms=3, label="candidate")
    ax[0].semilogy(np.arange(1, len(f) + 1), np.minimum.accumulate(f), "k-", label="best so far")
    ax[0].set_xlabel("evaluation")
    ax[0].set_ylabel("loss Σ ((sim − measured)/measured)²")
    ax[0].legend()
    if len(names) >= 2:
        sc = ax[1].scatter(a[:, 0], a[:, 1], c=np.log10(f), s=14, cmap="viridis")
        fig.colorbar(sc, ax=ax[1], label="log10 loss")
        ax[1].plot(a[best, 0], a[best, 1], "r*", ms=14, label="best")
        ax[1].set_ylabel(names[1])
    else:
        ax[1].semilogy(a[:, 0], f, "o", ms=3)
        ax[1].semilogy(a[best, 0], f[best], "r*", ms=14, label="best")
        ax[1].set_ylabel("loss")
    ax[1].set_xlabel(names[0])
    ax[1].legend()
    fig.suptitle("Calibration against %s: best %s, loss %.3g (%d candidates)"
                 % (", ".join("%s = %g" % kv for kv in targets.items()),
                    ", ".join("%s = %.4g" % (n, a[best, i]) for i, n in enumerate(names)), f[best], len(f)))
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
