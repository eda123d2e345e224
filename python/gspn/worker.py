"""A gspn worker in a few lines: decorate functions, call run().

    from gspn.worker import action, run

    @action("inspect")
    def inspect(ctx):
        print("inspecting", ctx.place)      # recorded as the agent's output
        return "t1"                         # fire t1; None lets the net decide

    run()

`plan-runner` starts the file as a worker (plan: `action = { worker = ["python3",
"robot_actions.py"], name = "inspect" }`) and sends it one JSON line per action; see
docs/actions.md for the protocol. Standard library only: importing it does not load the
engine (`gspn._native`), so a worker runs wherever the package's source is on the path.

A function returns a transition name (fire it), None (let the policy or the net's rates
decide), either with a duration as a pair (`return "t1", 2.5`: the outcome takes effect 2.5
model seconds later; in virtual time the time the function itself takes is not model time),
or raises (the action fails with the exception's message). Functions run one at a
time in the order requests come, unless declared `@action("name", concurrent=True)`: those
run on a thread pool, so slow functions (a sleep, a robot call) overlap. Inside a function,
print() goes to the run's journal as the agent's output; `ctx.cancelled` turns true when the
run stops or the action times out.

`@fallback` names a function that supplies actions registered nowhere else: called once
per unknown action name, it returns a function of ctx (kept for the next requests; it runs on
the thread pool) or None (the request fails: no such action).
"""

import json
import sys
import threading
from concurrent.futures import ThreadPoolExecutor

__all__ = ["action", "fallback", "run", "Context"]

_actions = {}
_out = sys.stdout
_lock = threading.Lock()
_local = threading.local()
_cancelled = set()
_fallback = []


def action(name, concurrent=False):
    """Registers the decorated function as the action `name`."""

    def register(f):
        _actions[name] = (f, concurrent)
        return f

    return register


def fallback(f):
    """Makes f(name) the supplier of actions no @action registered (see the module's doc)."""
    _fallback[:] = [f]
    return f


def _entry(name):
    """The (function, concurrent) of action `name`, asking the fallback once for a new name.
    Raises what the fallback raises."""
    entry = _actions.get(name)
    if entry is None and _fallback and isinstance(name, str):
        f = _fallback[0](name)
        if f is not None:
            entry = _actions[name] = (f, True)
    return entry


class Context:
    """One request: id, action, agent, place, robot, marking (dict), outputs (list), attempt,
    time, seed."""

    def __init__(self, req):
        self.__dict__.update(req)

    @property
    def cancelled(self):
        return self.id in _cancelled


def _send(msg):
    line = json.dumps(msg, separators=(",", ":")) + "\n"
    with _lock:
        _out.write(line)
        _out.flush()


class _Capture:
    """sys.stdout while run() runs: print() inside an action becomes an output message of
    its request; anything else goes to stderr, never into the protocol."""

    def __init__(self):
        self._pending = {}

    def write(self, text):
        rid = getattr(_local, "rid", None)
        if rid is None:
            return sys.stderr.write(text)
        buf = self._pending.get(rid, "") + text
        *lines, rest = buf.split("\n")
        for line in lines:
            _send({"id": rid, "output": line})
        self._pending[rid] = rest
        return len(text)

    def end(self, rid):
        rest = self._pending.pop(rid, "")
        if rest:
            _send({"id": rid, "output": rest})

    def flush(self):
        pass


_capture = _Capture()


def _handle(req, entry):
    rid = req["id"]
    _local.rid = rid
    try:
        if entry is None:
            reply = {"id": rid, "error": "no action named %r in this worker" % req.get("action")}
        else:
            result = entry[0](Context(req))
            after = None
            if isinstance(result, tuple):
                # (name or None, seconds): the outcome takes effect that many model seconds
                # later -- in virtual time, the only way an action takes model time.
                result, after = result
            if result is None:
                reply = {"id": rid, "decide": True}
            else:
                reply = {"id": rid, "fire": str(result)}
            if after is not None:
                reply["after"] = float(after)
    except Exception as e:  # the action fails; the worker lives on
        reply = {"id": rid, "error": "%s: %s" % (type(e).__name__, e)}
    finally:
        _local.rid = None
        _capture.end(rid)
    if rid in _cancelled:
        _cancelled.discard(rid)
        return
    _send(reply)


def run(threads=32):
    """Serves requests from stdin until it closes."""
    sys.stdout = _capture
    pool = None
    for line in sys.stdin:
        if not line.strip():
            continue
        req = json.loads(line)
        if "cancel" in req:
            _cancelled.add(req["cancel"])
            continue
        try:
            entry = _entry(req.get("action"))
        except Exception as e:  # a fallback that cannot supply it: this request fails
            _send({"id": req["id"], "error": "action %r: %s: %s" % (req.get("action"), type(e).__name__, e)})
            continue
        if entry is not None and entry[1]:
            if pool is None:
                pool = ThreadPoolExecutor(max_workers=threads)
            pool.submit(_handle, req, entry)
        else:
            _handle(req, entry)
    if pool is not None:
        pool.shutdown(wait=True)
