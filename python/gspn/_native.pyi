"""Type stubs of the engine (Rust, PyO3). Use the functions of :mod:`gspn`, not these."""

from os import PathLike

__version__: str

class Model:
    def describe(self) -> str: ...
    def to_text(self, format: str) -> str: ...
    def layout(self) -> str: ...

def load(
    path: str | PathLike[str], params: list[tuple[str, str]] | None = None, page: str | None = None
) -> Model: ...
def build(spec: str) -> Model: ...
def analyze(
    model: Model,
    steady: bool = True,
    transient: list[float] = ...,
    prob: list[str] = ...,
    max_states: int = 10_000_000,
    max_memory_mib: int = 4096,
) -> str: ...
def query(
    model: Model,
    queries: list[str],
    max_states: int = 10_000_000,
    max_memory_mib: int = 4096,
) -> list[float]: ...
def synthesize(
    model: Model,
    objective: str = "lra-max",
    goal: str | None = None,
    discount: float | None = None,
    gamma: float | None = None,
    reward: str | None = None,
    wait: bool | None = None,
    precision: float = 1e-9,
    method: str = "auto",
    max_states: int = 10_000_000,
) -> str: ...
def simulate(
    model: Model,
    seed: int | None = None,
    until: float | None = None,
    steps: int | None = None,
    runs: int | None = None,
) -> str: ...
def run(
    model: Model,
    actions: dict[str, object],
    seed: int | None = None,
    until: float | None = None,
    max_firings: int | None = None,
    time_scale: float | None = None,
    journal: str | None = None,
    robots: int | None = None,
) -> str: ...
