"""Many independent runs of one task — a parametric study (paper §5) or the candidates of a
calibration (paper Appendix C) — each in its own process, on this machine or on a Dask
cluster, with an append-only results store so that an interrupted sweep goes on where it
stopped.

A *task* is a Python function that takes keyword parameters and returns a dict of numbers
(or one number), named ``"package.module:function"`` or ``"path/to/file.py:function"``::

    from mpmsdem import sweep
    cases = [{"AR": 1.3, "L0_hb": 4}, {"AR": 2.0, "L0_hb": 24}]
    records = sweep.runAll("examples/parametric_study.py:runCase", cases, "runs.jsonl", workers=2)
    # the same on a cluster:           ..., scheduler="tcp://host:8786")

Every run is a fresh Python process (``sys.executable``) that imports the task and calls it
once, so a run cannot disturb the next one (YADE keeps one global scene per process) and a
crash (segfault, out of memory) fails that run only. With ``scheduler`` the runs go to Dask
workers, each of which starts the same kind of process: results are bit-identical to local
runs.

The store is a JSON-lines file, one record per finished or failed attempt, written by this
process only and flushed to disk at once::

    {"key": ..., "task": ..., "params": {...}, "status": "ok", "result": {...},
     "attempt": 1, "seconds": 12.3, "host": "node7", "finished": "2025-01-01T12:00:00"}

``key`` is the canonical JSON of ``params`` (floats written to round-trip exactly); a case
whose key has an ``"ok"`` record is never run again. Failed attempts are recorded with
``"status": "failed"`` and an ``"error"`` text, and retried up to ``retries`` times per
session; a later session tries them again.
"""
import concurrent.futures
import json
import math
import numbers
import os
import socket
import subprocess
import sys
import tempfile
import time
import uuid

_HERE = os.path.abspath(__file__)


class SweepError(RuntimeError):
    """A run failed on every attempt (the message lists the runs and their last errors)."""


# ---------------------------------------------------------------------------- tasks
def _splitTask(spec):
    if not isinstance(spec, str) or ":" not in spec:
        raise ValueError("task = %r: must be \"package.module:function\" or \"path/to/file.py:function\"" % (spec,))
    where, name = spec.rsplit(":", 1)
    if not where or not name.isidentifier():
        raise ValueError("task = %r: must be \"package.module:function\" or \"path/to/file.py:function\"" % (spec,))
    return where, name


def normaliseTask(spec):
    """``spec`` with a file path made absolute (runs may start in another folder; on a
    cluster the path must be the same on the workers, e.g. a shared file system)."""
    where, name = _splitTask(spec)
    if where.endswith(".py"):
        path = os.path.abspath(where)
        if not os.path.isfile(path):
            raise ValueError("task = %r: no such file %s" % (spec, path))
        return "%s:%s" % (path, name)
    return spec


def loadTask(spec):
    """The function a task names (see :func:`normaliseTask`); a file is imported as a module
    with its folder on ``sys.path``, as when it runs as a script."""
    import importlib
    import importlib.util
    where, name = _splitTask(spec)
    if where.endswith(".py"):
        path = os.path.abspath(where)
        modName = "_mpmsdem_task_" + os.path.splitext(os.path.basename(path))[0]
        module = sys.modules.get(modName)
        if module is None or getattr(module, "__file__", None) != path:
            if not os.path.isfile(path):
                raise ValueError("task = %r: no such file %s" % (spec, path))
            folder = os.path.dirname(path)
            if folder not in sys.path:
                sys.path.insert(0, folder)
            loader = importlib.util.spec_from_file_location(modName, path)
            module = importlib.util.module_from_spec(loader)
            sys.modules[modName] = module
            loader.loader.exec_module(module)
    else:
        module = importlib.import_module(where)
    fn = getattr(module, name, None)
    if not callable(fn):
        raise ValueError("task = %r: %s has no function %s" % (spec, where, name))
    return fn


def taskParameters(spec):
    """Names of the keyword parameters the task accepts, or None when it takes ``**kwargs``."""
    import inspect
    sig = inspect.signature(loadTask(spec))
    if any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values()):
        return None
    return [n for n, p in sig.parameters.items() if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]


# ---------------------------------------------------------------------------- keys
def _plainValue(v, where):
    if isinstance(v, bool) or v is None or isinstance(v, str):
        return v
    if isinstance(v, numbers.Integral):
        return int(v)
    if isinstance(v, numbers.Real):
        f = float(v)
        if not math.isfinite(f):
            raise ValueError("%s = %r: must be finite" % (where, v))
        return f
    if isinstance(v, (list, tuple)):
        return [_plainValue(x, "%s[%d]" % (where, i)) for i, x in enumerate(v)]
    raise ValueError("%s = %r: a run's parameters must be numbers, strings, booleans, None or lists of them"
                     % (where, v))


def canonicalParams(params):
    """``params`` as plain JSON values (numpy scalars to Python numbers); ValueError names a
    value that is not a finite number, string, boolean, None or list of them."""
    if not isinstance(params, dict) or not all(isinstance(k, str) for k in params):
        raise ValueError("params = %r: must be a dict with string keys" % (params,))
    return {k: _plainValue(v, "params[%r]" % k) for k, v in params.items()}


def runKey(params):
    """The store key of a run: canonical JSON of its parameters (sorted; floats as Python's
    shortest round-trip repr, so the same float vector always gives the same key)."""
    return json.dumps(canonicalParams(params), sort_keys=True, separators=(",", ":"))


# ---------------------------------------------------------------------------- store
def readStore(path):
    """All records of a store, in the order they were written (a half-written last line,
    left by a process killed while writing it, is skipped)."""
    if not os.path.exists(path):
        return []
    with open(path, "rb") as f:
        data = f.read()
    return _parse(path, data[:data.rfind(b"\n") + 1])


def _parse(path, data):
    records = []
    for n, line in enumerate(data.decode("utf-8").splitlines(), 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
        except ValueError:
            raise ValueError("store %s, line %d: not a JSON record (%.60s...); was the file edited? Move it away to "
                             "start afresh" % (path, n, line)) from None
        if not isinstance(rec, dict) or "key" not in rec or "status" not in rec:
            raise ValueError("store %s, line %d: not a run record (needs key and status)" % (path, n))
        records.append(rec)
    return records


class Store:
    """The writable results store of one sweep (see the module text). Opening it takes an
    exclusive lock (``<path>.lock``), so two sweeps cannot write the same file; a half-written
    last line left by a killed process is cut off.

    :param path: the JSON-lines file [created with its folder when missing].
    :param task: the task spec the records must belong to (None: any); a store holding runs
        of another task is refused, since its results would be reused for the wrong function.
    """

    def __init__(self, path, task=None):
        import fcntl
        self.path = os.path.abspath(path)
        os.makedirs(os.path.dirname(self.path), exist_ok=True)
        self._lock = open(self.path + ".lock", "a")
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self._lock.close()
            raise RuntimeError("store %s is in use by another sweep (lock %s.lock held); wait for it or use another "
                               "store" % (self.path, self.path)) from None
        with open(self.path, "a+b") as f:
            f.seek(0)
            data = f.read()
            end = data.rfind(b"\n") + 1
            if end != len(data):  # a record cut short by a kill: it never counted, drop it
                f.truncate(end)
        self.records = _parse(self.path, data[:end])
        if task is not None:
            name = _taskName(task)
            other = {_taskName(r["task"]) for r in self.records if r.get("task")} - {name}
            if other:
                self.close()
                raise ValueError("store %s holds runs of task %s, not %s: use another store for this task"
                                 % (self.path, ", ".join(sorted(other)), name))
        self._ok = {r["key"]: r for r in self.records if r["status"] == "ok"}

    def finished(self, key):
        """The ``"ok"`` record of ``key``, or None."""
        return self._ok.get(key)

    def append(self, record):
        """Write one record and flush it to disk before returning."""
        line = json.dumps(record, sort_keys=True) + "\n"
        with open(self.path, "a") as f:
            f.write(line)
            f.flush()
            os.fsync(f.fileno())
        self.records.append(record)
        if record["status"] == "ok":
            self._ok[record["key"]] = record

    def close(self):
        if not self._lock.closed:
            self._lock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _taskName(spec):
    # A file task is named by file name and function: the same study run from another folder
    # or machine keeps its store.
    where, name = spec.rsplit(":", 1)
    return "%s:%s" % (os.path.basename(where) if where.endswith(".py") else where, name)


# ---------------------------------------------------------------------------- one attempt
def _tail(path, lines=15):
    try:
        with open(path, errors="replace") as f:
            return "".join(f.readlines()[-lines:]).rstrip()
    except OSError:
        return ""


def attempt(task, params, timeout=None, threads=1, live=None):
    """Run ``task(**params)`` once in a new process and return its record (without key and
    attempt number). Runs where it is called: in this process's thread pool, or on a Dask
    worker. ``live``: a set the process is kept in while it runs (so that an interrupted
    sweep can stop it)."""
    start = time.time()
    rec = {"task": task, "params": params, "host": socket.gethostname()}
    with tempfile.TemporaryDirectory(prefix="mpmsdem-run-") as tmp:
        request, answer, log = (os.path.join(tmp, n) for n in ("request.json", "result.json", "log.txt"))
        with open(request, "w") as f:
            json.dump({"task": task, "params": params, "result": answer}, f)
        env = dict(os.environ, OMP_NUM_THREADS=str(threads))
        with open(log, "w") as out:
            proc = subprocess.Popen([sys.executable, _HERE, request], stdout=out, stderr=subprocess.STDOUT, env=env)
            if live is not None:
                live.add(proc)
            try:
                code = proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
                code = None
            finally:
                if live is not None:
                    live.discard(proc)
        rec["seconds"] = time.time() - start
        rec["finished"] = time.strftime("%Y-%m-%dT%H:%M:%S")
        if code == 0 and os.path.exists(answer):
            with open(answer) as f:
                rec.update(status="ok", result=json.load(f))
            return rec
        if code is None:
            why = "timed out after %g s" % timeout
        elif code < 0:
            why = "killed by signal %d" % -code
        else:
            why = "exit code %d" % code
        rec.update(status="failed", error="%s; last output:\n%s" % (why, _tail(log)))
        return rec


def _child(request):
    # The process that runs one attempt: started as a file, so that the package is imported
    # only if the task needs it. Its own folder (the package) would shadow top-level modules
    # named like ours; the package's parent takes its place, so `import mpmsdem` finds the
    # same installation as the parent process.
    sys.path[0] = os.path.dirname(os.path.dirname(_HERE))
    with open(request) as f:
        req = json.load(f)
    result = loadTask(req["task"])(**req["params"])
    if isinstance(result, numbers.Real) and not isinstance(result, bool):
        result = {"value": float(result)}
    if not isinstance(result, dict):
        raise TypeError("task %s returned %r: must return a dict of JSON values or a number" % (req["task"], result))
    tmp = req["result"] + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, default=_jsonDefault)
    os.rename(tmp, req["result"])


def _jsonDefault(v):
    if isinstance(v, numbers.Integral):
        return int(v)
    if isinstance(v, numbers.Real):
        return float(v)
    if hasattr(v, "tolist"):
        return v.tolist()
    raise TypeError("task result holds %r, which is not a JSON value" % (v,))


# ---------------------------------------------------------------------------- executor
def _validate(workers, retries, timeout, threads, scheduler):
    if not (isinstance(workers, numbers.Integral) and workers >= 1):
        raise ValueError("workers = %r: must be an integer >= 1 (local processes at a time)" % (workers,))
    if not (isinstance(retries, numbers.Integral) and retries >= 0):
        raise ValueError("retries = %r: must be an integer >= 0 (extra attempts of a failed run)" % (retries,))
    if timeout is not None and not (isinstance(timeout, numbers.Real) and timeout > 0):
        raise ValueError("timeout = %r s: must be > 0, or None for no limit" % (timeout,))
    if not (isinstance(threads, numbers.Integral) and threads >= 1):
        raise ValueError("threads = %r: must be an integer >= 1 (OMP_NUM_THREADS of each run)" % (threads,))
    if scheduler is not None and not (isinstance(scheduler, str) and "://" in scheduler):
        raise ValueError("scheduler = %r: must be a Dask scheduler address such as tcp://host:8786, or None for "
                         "local processes" % (scheduler,))


def describeParams(params, fmt="%.6g"):
    """``name=value ...`` of a run's parameters for progress lines (floats with ``fmt``)."""
    return " ".join("%s=%s" % (k, fmt % v if isinstance(v, float) else v) for k, v in params.items())


class Executor:
    """Runs a task on lists of parameter sets (:meth:`map`), reusing and extending a store.

    :param task: ``"package.module:function"`` or ``"path/to/file.py:function"``; the
        function takes the parameters as keywords and returns a dict of JSON values (or a
        number, stored as ``{"value": x}``).
    :param store: path of the JSON-lines results store (created when missing).
    :param workers: local processes at a time, >= 1 (default 1; ignored with ``scheduler``:
        the cluster's workers decide).
    :param scheduler: None (default): run on this machine; ``"tcp://host:port"``: the
        address of a running Dask scheduler whose workers run the attempts (they need
        mpmsdem installed and file tasks at the same path).
    :param retries: extra attempts of a failed run in this session, >= 0 (default 2).
    :param timeout: limit of one attempt [s] (default None: none); an attempt over it is
        killed and counts as failed.
    :param threads: OMP_NUM_THREADS of each run, >= 1 (default 1).
    :param progress: True (default): one line per finished run on stdout; False: none; or a
        callable ``f(text)`` that receives the lines.
    :param describe: callable ``f(record) -> str`` adding text to a finished run's line.
    :param connectTimeout: seconds to wait for the scheduler (default 10).

    Counters after :meth:`map`: ``started`` (attempts launched), ``reused`` (cases answered
    from the store), ``failures`` (failed attempts).
    """

    def __init__(self, task, store, workers=1, scheduler=None, retries=2, timeout=None, threads=1, progress=True,
                 describe=None, connectTimeout=10):
        _validate(workers, retries, timeout, threads, scheduler)
        self.task = normaliseTask(task)
        self.workers, self.retries = int(workers), int(retries)
        self.timeout, self.threads, self.describe = timeout, int(threads), describe
        self._say = progress if callable(progress) else (print if progress else (lambda text: None))
        self.started = self.reused = self.failures = 0
        self._client = self._pool = None
        self._live = set()
        if scheduler is not None:
            self._client = _connect(scheduler, connectTimeout)
        try:
            self.store = Store(store, task=self.task)
        except BaseException:
            if self._client is not None:
                self._client.close()
            raise

    def close(self):
        self.store.close()
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
        if self._client is not None:
            self._client.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def map(self, cases):
        """Run every case not yet in the store and return one record per case, in order:
        the ``"ok"`` record, or the last failed one of a case that failed every attempt."""
        cases = [canonicalParams(c) for c in cases]
        keys = [runKey(c) for c in cases]
        todo, seen = [], set()
        for k, c in zip(keys, cases):
            if k in seen or self.store.finished(k):
                continue
            seen.add(k)
            todo.append((k, c))
        self.reused += len(set(keys) - seen)
        final = {}
        if todo:
            self._progress = {"done": len(set(keys) - seen), "total": len(set(keys)), "t0": time.time(), "computed": 0}
            try:
                self._run(todo, final)
            except BaseException:
                for p in list(self._live):  # an interrupted sweep leaves no run behind
                    p.kill()
                raise
        return [self.store.finished(k) or final[k] for k in keys]

    # -- backends
    def _run(self, todo, final):
        params = dict(todo)
        tries, owner = {}, {}  # attempts per run key; run key of each pending future
        queue = None
        if self._client is not None:
            from distributed import as_completed
            queue = as_completed()
        elif self._pool is None:
            self._pool = concurrent.futures.ThreadPoolExecutor(max_workers=self.workers)

        def launch(k):
            tries[k] = tries.get(k, 0) + 1
            self.started += 1
            if queue is None:
                fut = self._pool.submit(attempt, self.task, params[k], self.timeout, self.threads, self._live)
            else:
                name = "mpmsdem-%s" % uuid.uuid4().hex  # readable in the Dask dashboard, never reused
                fut = self._client.submit(attempt, self.task, params[k], self.timeout, self.threads, key=name,
                                          pure=False)
                queue.add(fut)
            owner[fut] = k

        for k, _ in todo:
            launch(k)
        while owner:
            if queue is None:
                fut = next(iter(concurrent.futures.wait(owner, return_when=concurrent.futures.FIRST_COMPLETED)[0]))
            else:
                fut = next(queue)
            k = owner.pop(fut)
            rec = self._result(fut, params[k])
            rec.update(key=k, attempt=tries[k])
            self.store.append(rec)
            if rec["status"] == "ok":
                self._progress["computed"] += 1
                self._progress["done"] += 1
                self._line(rec, "ok")
            elif tries[k] <= self.retries:
                self.failures += 1
                self._line(rec, "failed, retrying (attempt %d of %d)" % (tries[k], self.retries + 1))
                launch(k)
            else:
                self.failures += 1
                self._progress["done"] += 1
                self._line(rec, "FAILED after %d attempts" % tries[k])
                final[k] = rec

    def _result(self, fut, params):
        try:
            return fut.result()
        except Exception as e:  # the worker died or was lost: this attempt failed, not the sweep
            return {"task": self.task, "params": params, "status": "failed", "error": "%s: %s" % (type(e).__name__, e),
                    "finished": time.strftime("%Y-%m-%dT%H:%M:%S")}

    def _line(self, rec, state):
        p = self._progress
        n = 20 * p["done"] // max(1, p["total"])
        text = "[%s%s] %*d/%d %s %s" % ("#" * n, "-" * (20 - n), len(str(p["total"])), p["done"], p["total"], state,
                                       describeParams(rec["params"]))
        if rec["status"] == "ok":
            text += " (%.1f s)" % rec.get("seconds", 0.0)
            if self.describe:
                text += " " + self.describe(rec)
            left = p["total"] - p["done"]
            if left and p["computed"]:
                eta = (time.time() - p["t0"]) / p["computed"] * left
                text += ", ~%s left" % _duration(eta)
        else:
            text += "\n    " + rec.get("error", "").replace("\n", "\n    ")
        self._say(text)


def _duration(s):
    s = int(round(s))
    return "%d:%02d:%02d" % (s // 3600, s // 60 % 60, s % 60)


def _connect(address, timeout):
    try:
        from distributed import Client
    except ImportError:
        raise RuntimeError("scheduler = %r needs Dask (Debian packages python3-dask and python3-distributed: make "
                           "deps)" % address) from None
    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError) as e:
        raise ConnectionError("scheduler = %r: no Dask scheduler answered within %g s (%s). Start one (dask-scheduler, "
                              "then dask-worker ADDRESS on each node, or a dask-jobqueue cluster) or leave the "
                              "scheduler out to run local processes" % (address, timeout, e)) from None


def runAll(task, cases, store, workers=1, scheduler=None, retries=2, timeout=None, threads=1, progress=True,
           describe=None):
    """Run ``task`` on every parameter dict of ``cases`` (see :class:`Executor` for the
    arguments) and return their records in order; runs already in ``store`` are not run
    again. Failed runs come back as records with ``"status": "failed"``; the caller decides
    whether that is fatal (:func:`failed` lists them)."""
    with Executor(task, store, workers=workers, scheduler=scheduler, retries=retries, timeout=timeout, threads=threads,
                  progress=progress, describe=describe) as ex:
        records = ex.map(cases)
        if progress:
            ex._say("%d runs: %d computed now, %d from the store, %d failed (%d failed attempts); store %s"
                    % (len(records), ex.started - ex.failures, ex.reused, len(failed(records)), ex.failures,
                       ex.store.path))
        return records


def failed(records):
    """The records of runs that failed every attempt."""
    return [r for r in records if r["status"] != "ok"]


if __name__ == "__main__":
    _child(sys.argv[1])
