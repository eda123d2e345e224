"""The Python API over the native engine (``gspn._native``)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence, Union, overload

import numpy as np

from . import _native
from ._svg import net_svg

PathLike = Union[str, "os.PathLike[str]"]

__all__ = [
    "Net",
    "Place",
    "Transition",
    "Arc",
    "immediate",
    "exponential",
    "load",
    "analyze",
    "synthesize",
    "simulate",
    "run",
    "Analysis",
    "Measures",
    "Synthesis",
    "Simulation",
    "Estimate",
    "RunResult",
]


# --------------------------------------------------------------------------- nets


@dataclass(frozen=True)
class Place:
    """A place: its name, initial tokens and capacity (``None``: unbounded)."""

    name: str
    initial: int
    capacity: int | None = None


@dataclass(frozen=True)
class Transition:
    """A transition: ``kind`` is ``"immediate"`` (``weight``, ``priority``) or
    ``"exponential"`` (``rate`` per server, ``servers``: a count or ``"infinite"``)."""

    name: str
    kind: str
    rate: float | None = None
    servers: int | str | None = None
    weight: float | None = None
    priority: int | None = None


@dataclass(frozen=True)
class Arc:
    """An arc: ``kind`` is ``"input"`` (place → transition), ``"output"`` (transition →
    place) or ``"inhibitor"``; ``weight`` its multiplicity."""

    kind: str
    place: str
    transition: str
    weight: int = 1


def immediate(weight: float = 1.0, priority: int = 1) -> dict[str, Any]:
    """An immediate transition for :meth:`Net.build` (weight 0: a decision for a policy)."""
    return {"weight": float(weight), "priority": int(priority)}


def exponential(rate: float, servers: int | str = 1) -> dict[str, Any]:
    """An exponential transition for :meth:`Net.build`: ``rate`` per server; ``servers`` a
    count or ``"infinite"``."""
    return {"rate": float(rate), "servers": servers}


class Net:
    """A net, or a plan with its net (read by :func:`load` or made by :meth:`Net.build`).

    ``places``, ``transitions`` and ``arcs`` are plain data in the net's order; ``marking`` is
    the initial marking by place name. A plan also carries its policy, rewards and roles:
    :func:`analyze` analyses it under its policy, :func:`synthesize` optimises it,
    :func:`run` executes it.
    """

    def __init__(self, model: "_native.Model") -> None:
        self._model = model
        d = json.loads(model.describe())
        self.name: str = d["name"]
        self.source: str = d["source"]
        self.is_plan: bool = d["is_plan"]
        self.places: list[Place] = [Place(**p) for p in d["places"]]
        self.transitions: list[Transition] = [Transition(**t) for t in d["transitions"]]
        self.arcs: list[Arc] = [Arc(**a) for a in d["arcs"]]
        self.rewards: list[str] = d["rewards"]
        self.controllable: list[str] = d["controllable"]
        self.policy_rules: int = d["policy_rules"]
        self.warnings: list[str] = d["warnings"]

    @property
    def marking(self) -> dict[str, int]:
        """The initial marking: tokens by place name, every place."""
        return {p.name: p.initial for p in self.places}

    @property
    def place_names(self) -> list[str]:
        return [p.name for p in self.places]

    @property
    def transition_names(self) -> list[str]:
        return [t.name for t in self.transitions]

    @classmethod
    def build(
        cls,
        name: str,
        places: Mapping[str, int | Place],
        transitions: Mapping[str, Mapping[str, Any]],
        arcs: Iterable[Sequence[Any] | Arc],
    ) -> "Net":
        """Makes a net in code.

        ``places`` maps names to initial tokens (or :class:`Place`); ``transitions`` maps
        names to :func:`immediate` or :func:`exponential`; each arc is ``(source, target)``,
        ``(source, target, weight)`` — a place → transition pair is an input, transition →
        place an output — or an :class:`Arc` (for inhibitors)::

            net = gspn.Net.build(
                "on-off",
                places={"on": 1, "off": 0},
                transitions={"fail": gspn.exponential(1.0), "repair": gspn.exponential(3.0)},
                arcs=[("on", "fail"), ("fail", "off"), ("off", "repair"), ("repair", "on")],
            )
        """
        ps = []
        for pname, v in places.items():
            if isinstance(v, Place):
                ps.append({"name": pname, "initial": v.initial, "capacity": v.capacity})
            else:
                ps.append({"name": pname, "initial": int(v), "capacity": None})
        ts = [{"name": tname, **dict(spec)} for tname, spec in transitions.items()]
        place_set = set(places)
        arcs_out = []
        for a in arcs:
            if isinstance(a, Arc):
                arcs_out.append(
                    {"kind": a.kind, "place": a.place, "transition": a.transition, "weight": a.weight}
                )
                continue
            source, target, *rest = a
            weight = int(rest[0]) if rest else 1
            if source in place_set:
                arcs_out.append({"kind": "input", "place": source, "transition": target, "weight": weight})
            elif target in place_set:
                arcs_out.append({"kind": "output", "place": target, "transition": source, "weight": weight})
            else:
                raise _errors().InputError(f"arc {source!r} → {target!r}: neither end is a place")
        spec = {"name": name, "places": ps, "transitions": ts, "arcs": arcs_out}
        return cls(_native.build(json.dumps(spec)))

    def to_pnpro(self) -> str:
        """The net as a GreatSPN ``.PNPRO`` document."""
        return self._model.to_text("pnpro")

    def to_pnml(self) -> str:
        """The net as PNML (with the timed extension)."""
        return self._model.to_text("pnml")

    def to_dot(self) -> str:
        """The net as a Graphviz drawing."""
        return self._model.to_text("dot")

    def save(self, path: PathLike) -> None:
        """Writes the net in the format ``path``'s extension names (.PNPRO, .pnml, .xml, .dot)."""
        ext = Path(path).suffix.lower()
        fmt = {".pnpro": "pnpro", ".pnml": "pnml", ".xml": "pipe", ".dot": "dot"}.get(ext)
        if fmt is None:
            raise _errors().InputError(
                f"{path}: cannot tell the format from the extension (use .PNPRO, .pnml, .xml or .dot)"
            )
        Path(path).write_text(self._model.to_text(fmt), encoding="utf-8")

    def _repr_svg_(self) -> str:
        return net_svg(self, json.loads(self._model.layout()))

    def __repr__(self) -> str:
        kind = "plan" if self.is_plan else "net"
        return (
            f"<gspn.Net {self.name!r} ({kind}): {len(self.places)} places, "
            f"{len(self.transitions)} transitions>"
        )


def _errors():
    from . import errors

    return errors


def load(path: PathLike, params: Mapping[str, Any] | None = None, page: str | None = None) -> Net:
    """Reads a net (GreatSPN ``.PNPRO``, PNML, PIPE ``.xml``) or a plan (``.toml``).

    ``params`` set a PNPRO template's parameters (as ``--param NAME=VALUE``); ``page`` picks
    a page of a multi-page PNPRO. Bad input raises :class:`gspn.InputError` with the file,
    line and column.
    """
    pairs = [(str(k), str(v)) for k, v in (params or {}).items()]
    return Net(_native.load(os.fspath(path), pairs, page))


def _net(net_or_plan: Net | PathLike) -> Net:
    if isinstance(net_or_plan, Net):
        return net_or_plan
    return load(net_or_plan)


# --------------------------------------------------------------------------- analysis


@dataclass
class Measures:
    """Measures of one instant (``time``) or of the steady state (``time`` is ``None``).

    Arrays follow the net's place and transition order (``places``, ``transitions``);
    ``by_place``/``by_transition`` give them as dicts.
    """

    places: list[str]
    transitions: list[str]
    mean_tokens: np.ndarray
    throughput: np.ndarray
    prob_nonempty: np.ndarray | None = None
    mean_wait: np.ndarray | None = None
    time: float | None = None
    ergodic: bool | None = None
    probability: dict[str, float] = field(default_factory=dict)
    rewards: dict[str, dict[str, float]] = field(default_factory=dict)

    @classmethod
    def _from(cls, net: Net, d: Mapping[str, Any]) -> "Measures":
        ps, ts = net.place_names, net.transition_names

        def arr(m: Mapping[str, Any] | None, names: list[str]) -> np.ndarray | None:
            if m is None:
                return None
            return np.array([np.nan if m[n] is None else m[n] for n in names], dtype=float)

        return cls(
            places=ps,
            transitions=ts,
            mean_tokens=arr(d["mean_tokens"], ps),
            throughput=arr(d["throughput"], ts),
            prob_nonempty=arr(d.get("prob_nonempty"), ps),
            mean_wait=arr(d.get("mean_wait"), ps),
            time=d.get("t"),
            ergodic=d.get("ergodic"),
            probability=dict(d.get("probability") or {}),
            rewards=dict(d.get("rewards") or {}),
        )

    def by_place(self, values: np.ndarray | None = None) -> dict[str, float]:
        v = self.mean_tokens if values is None else values
        return dict(zip(self.places, v.tolist()))

    def by_transition(self, values: np.ndarray | None = None) -> dict[str, float]:
        v = self.throughput if values is None else values
        return dict(zip(self.transitions, v.tolist()))

    def _repr_html_(self) -> str:
        rows = "".join(
            f"<tr><td>{p}</td><td>{m:.9g}</td></tr>" for p, m in zip(self.places, self.mean_tokens)
        )
        rows += "".join(
            f"<tr><td>{t}</td><td>{x:.9g}</td></tr>" for t, x in zip(self.transitions, self.throughput)
        )
        when = "steady state" if self.time is None else f"t = {self.time}"
        return f"<table><caption>{when}</caption><tr><th></th><th>E[tokens] / throughput</th></tr>{rows}</table>"


@dataclass
class Analysis:
    """What :func:`analyze` found: ``state_space`` (reachable, tangible, vanishing, edges,
    bounds, deadlocks, liveness, invariants: the CLI's JSON), ``steady`` and ``transient``
    measures, and ``report``, the whole JSON document ``plan-runner analyze --json`` prints."""

    analysed: str
    state_space: dict[str, Any]
    steady: Measures | None
    transient: list[Measures]
    report: dict[str, Any]


def analyze(
    net_or_plan: Net | PathLike,
    steady: bool = True,
    transient: Sequence[float] = (),
    prob: Sequence[str] = (),
    max_states: int = 10_000_000,
    max_memory_mib: int = 4096,
) -> Analysis:
    """Exact analysis: the state space and its properties, the steady state (limiting
    distribution from the initial marking; a plan's rewards as long-run rates) and the
    measures at each time in ``transient``; ``prob`` adds the probability of marking
    predicates such as ``"P1 > 0 && P3 == 0"``. A plan is analysed under its policy.

    The GIL is released while it runs; Ctrl-C cancels it (KeyboardInterrupt).
    """
    net = _net(net_or_plan)
    steady_wanted = steady or not transient
    text = _native.analyze(
        net._model, steady_wanted, [float(t) for t in transient], list(prob), max_states, max_memory_mib
    )
    report = json.loads(text)
    st = report.get("steady_state")
    return Analysis(
        analysed=report["analysed"],
        state_space=report["state_space"],
        steady=None if st is None else Measures._from(net, st),
        transient=[Measures._from(net, p) for p in report["transient"]],
        report=report,
    )


@overload
def query(
    net_or_plan: Net | PathLike, queries: str, max_states: int = ..., max_memory_mib: int = ...
) -> float: ...
@overload
def query(
    net_or_plan: Net | PathLike,
    queries: Sequence[str],
    max_states: int = ...,
    max_memory_mib: int = ...,
) -> list[float]: ...
def query(
    net_or_plan: Net | PathLike,
    queries: str | Sequence[str],
    max_states: int = 10_000_000,
    max_memory_mib: int = 4096,
) -> float | list[float]:
    """The value of a query in Storm's/PRISM's syntax, as ``plan-runner analyze --query``
    answers it: ``"P=? [F<=600 done=1]"`` (time-bounded reachability), ``"P=? [F φ]"``,
    ``"P=? [φ1 U<=t φ2]"``, ``"P=? [G<=t φ]"``, ``"T=? [F φ]"`` (expected time, ``inf``
    when φ may never hold), ``"S=? [φ]"`` (long-run probability), ``'R{"name"}=? [S]'``,
    ``[C<=t]`` and ``[F φ]`` over a plan's rewards, and ``Pmax=?``/``Pmin=?``/``Tmin=?``…
    over a plan's controllable transitions. A plan is read under its policy.

    One query gives a float, a list of queries a list in the same order (the state space
    is built once). A malformed query raises :class:`gspn.InputError` with the ``column``
    in the query text. The GIL is released while it runs; Ctrl-C cancels it.
    """
    net = _net(net_or_plan)
    single = isinstance(queries, str)
    texts = [queries] if single else [str(q) for q in queries]
    values = _native.query(net._model, texts, max_states, max_memory_mib)
    return values[0] if single else list(values)


# --------------------------------------------------------------------------- synthesis


@dataclass
class Synthesis:
    """The optimal value (``value`` in ``[lower, upper]``), the model's size and the policy:
    ``rules`` (one per decision marking: ``{"marking": {...}, "choose": name}``) and
    ``compressed_rules`` (the same decisions as partial-marking rules).
    :meth:`policy_toml` gives them as a plan's ``[[policy]]`` tables; :meth:`write` writes a
    runnable plan."""

    objective: str
    value: float
    lower: float
    upper: float
    method: str
    iterations: int
    states: int
    choices: int
    rules: list[dict[str, Any]]
    compressed_rules: list[dict[str, Any]]
    report: dict[str, Any]
    net: Net

    def policy_toml(self, compact: bool = False) -> str:
        """The policy as ``[[policy]]`` tables (exact markings, or compressed with
        ``compact=True``)."""
        out = []
        for r in self.compressed_rules if compact else self.rules:
            marking = ", ".join(f"{_key(p)} = {k}" for p, k in r["marking"].items())
            choose = r["choose"]
            if isinstance(choose, str):
                choose = {choose: 1.0}
            chosen = ", ".join(f"{_key(t)} = {float(p)!r}" for t, p in choose.items())
            out.append("\n[[policy]]\n")
            out.append(f"marking = {{ {marking} }}\n" if marking else "marking = {}\n")
            if r.get("partial"):
                out.append("partial = true\n")
            out.append(f"choose = {{ {chosen} }}\n")
        return "".join(out)

    def write(self, path: PathLike, compact: bool = False) -> None:
        """Writes a plan that runs this policy: the source plan (its ``net`` path made
        relative to ``path``'s directory) or, for a bare net, a plan naming it, followed by
        the ``[[policy]]`` tables."""
        path = Path(path)
        source = Path(self.net.source)
        header = (
            f"# policy synthesised by gspn.synthesize\n"
            f"# objective: {self.objective}, optimal value {self.value} in [{self.lower}, {self.upper}]\n"
        )
        if self.net.is_plan:
            body = _rebase_plan(source, path.parent)
        else:
            body = f"net = {json.dumps(os.path.relpath(source.resolve(), path.parent.resolve()))}\n"
        path.write_text(header + body + self.policy_toml(compact), encoding="utf-8")


def _key(name: str) -> str:
    if name and all(c.isascii() and (c.isalnum() or c in "_-") for c in name):
        return name
    return json.dumps(name)


def _rebase_plan(plan: Path, out_dir: Path) -> str:
    """The plan's text with its top-level ``net = "..."`` made relative to ``out_dir``."""
    import tomllib

    text = plan.read_text(encoding="utf-8")
    net_value = tomllib.loads(text)["net"]
    new = json.dumps(os.path.relpath((plan.parent / net_value).resolve(), out_dir.resolve()))
    lines = text.splitlines(keepends=True)
    for i, line in enumerate(lines):
        stripped = line.lstrip()
        if stripped.startswith("[") and not stripped.startswith("[["):
            break  # top-level keys come before the first table
        if stripped.startswith("net") and stripped[3:].lstrip().startswith("="):
            comment = line.find("#", line.find("=") + 1 + len(repr(net_value)))
            tail = "  " + line[comment:] if comment >= 0 else "\n"
            lines[i] = f"net = {new}{tail if tail.endswith(chr(10)) else tail + chr(10)}"
            break
    out = "".join(lines)
    return out if out.endswith("\n") else out + "\n"


def synthesize(
    net_or_plan: Net | PathLike,
    objective: str = "lra-max",
    goal: str | None = None,
    discount: float | None = None,
    gamma: float | None = None,
    reward: str | None = None,
    wait: bool | None = None,
    precision: float = 1e-9,
    method: str = "auto",
    max_states: int = 10_000_000,
) -> Synthesis:
    """The policy optimising ``objective`` on a plan (its ``[rewards.NAME]``, controllable
    transitions) or a net (zero-weight immediate transitions are the decisions): the CLI's
    ``synthesize`` (``lra``, ``reach``, ``total``, ``time`` with ``goal``, ``discounted`` with
    ``discount``, ``discounted-per-step`` with ``gamma``; each ``-max`` or ``-min``)."""
    net = _net(net_or_plan)
    d = json.loads(
        _native.synthesize(
            net._model, objective, goal, discount, gamma, reward, wait, precision, method, max_states
        )
    )
    return Synthesis(
        objective=d["objective"],
        value=float(d["value"]),
        lower=float(d["lower"]),
        upper=float(d["upper"]),
        method=d["method"],
        iterations=d["iterations"],
        states=d["states"],
        choices=d["choices"],
        rules=d["rules"],
        compressed_rules=d["compressed_rules"],
        report=d,
        net=net,
    )


# --------------------------------------------------------------------------- simulation


@dataclass(frozen=True)
class Estimate:
    """A Monte-Carlo estimate with its 95% confidence interval (``None`` with one run)."""

    mean: float
    lo: float | None
    hi: float | None


@dataclass
class Simulation:
    """:func:`simulate`'s answer: ``steps`` (time, transition, marking) for one run, or
    ``mean_tokens``/``throughput`` estimates over ``runs`` runs."""

    seed: int
    runs: int
    steps: list[dict[str, Any]]
    mean_tokens: dict[str, Estimate]
    throughput: dict[str, Estimate]
    report: dict[str, Any]

    @property
    def times(self) -> np.ndarray:
        return np.array([s["time"] for s in self.steps], dtype=float)


def simulate(
    net_or_plan: Net | PathLike,
    seed: int | None = None,
    until: float | None = None,
    steps: int | None = None,
    runs: int | None = None,
) -> Simulation:
    """The token game: with ``runs``, estimates of mean tokens and throughputs with 95%
    intervals; without, one run's trace. ``until`` (model time) or ``steps`` bound each run."""
    net = _net(net_or_plan)
    d = json.loads(_native.simulate(net._model, seed, until, steps, runs))
    est = lambda m: {k: Estimate(v["mean"], v["lo"], v["hi"]) for k, v in m.items()}  # noqa: E731
    return Simulation(
        seed=d["seed"],
        runs=d.get("runs", 1),
        steps=d.get("steps", []),
        mean_tokens=est(d.get("mean_tokens", {})),
        throughput=est(d.get("throughput", {})),
        report=d,
    )


# --------------------------------------------------------------------------- runs


@dataclass
class RunResult:
    """A run's summary (``plan-runner run --json``): why it stopped, firings, model time,
    the final marking, and the journal's path when one was written."""

    stopped: str
    firings: int
    time: float
    final_marking: dict[str, int]
    seed: int
    exit_code: int
    journal: str | None
    summary: dict[str, Any]


def run(
    plan: Net | PathLike,
    actions: Mapping[str, Callable[..., Any]] | None = None,
    *,
    seed: int | None = None,
    until: float | None = None,
    max_firings: int | None = None,
    time_scale: float | None = None,
    journal: PathLike | None = None,
    robots: int | None = None,
) -> RunResult:
    """Executes a plan on agents. ``actions`` maps a place (or an action name the plan uses)
    to a Python function of an :class:`gspn.ActionContext`, plain or ``async def``; it
    answers a transition name, ``None`` (the net decides), or ``(name, seconds)``. Other
    places keep the plan's actions. Ctrl-C stops the run cleanly and raises
    KeyboardInterrupt."""
    net = _net(plan)
    jpath = None if journal is None else os.fspath(journal)
    d = json.loads(
        _native.run(
            net._model, dict(actions or {}), seed, until, max_firings, time_scale, jpath, robots
        )
    )
    return RunResult(
        stopped=d["stopped"],
        firings=d["firings"],
        time=d["time"],
        final_marking=d["final_marking"],
        seed=d["seed"],
        exit_code=d["exit_code"],
        journal=jpath,
        summary=d,
    )
