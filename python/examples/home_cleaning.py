# %% [markdown]
# # Home cleaning, from model to run, in Python
#
# The GSPNR toolbox's home scenario (`plans/home-cleaning/`): three robots in three rooms,
# each choosing to mop, vacuum or move on. We analyse the plan, synthesise the policy that
# earns the most cleaning reward per unit of time, run it with one place's action written
# in Python, and plot the result. Cells (`# %%`) run in Jupyter or VS Code; as a script:
#
#     pip install ./python matplotlib
#     python python/examples/home_cleaning.py   # writes home_cleaning_policy.toml and
#                                               # home_cleaning.png in the current directory

# %%
from collections import Counter
from pathlib import Path

import gspn

HERE = Path(__file__).resolve().parent
PLAN = HERE.parents[1] / "plans" / "home-cleaning" / "plan.toml"

plan = gspn.load(PLAN)
print(plan)  # in Jupyter, `plan` alone draws the net
print("decisions:", len(plan.controllable), "controllable transitions")

# %% [markdown]
# ## The net as it stands: the weights of the zero-weight decisions are equal (ties).

# %%
state = gspn.analyze(plan, transient=[1, 5, 20])
print(state.state_space["reachable"], "reachable markings")
print("reward per unit time without a policy:", state.steady.rewards)

# %% [markdown]
# ## The optimal policy (long-run average reward, maximised)

# %%
best = gspn.synthesize(plan, objective="lra-max")
print(f"optimal reward rate {best.value:.9f} in [{best.lower:.9f}, {best.upper:.9f}]")
print(len(best.rules), "decision markings,", len(best.compressed_rules), "compressed rules")
policy_plan = Path("home_cleaning_policy.toml").resolve()
best.write(policy_plan)
under_policy = gspn.analyze(policy_plan)
print("analysed under it:", under_policy.steady.rewards)

# %% [markdown]
# ## Run the policy on agents, with the mopping of room 2 written in Python

# %%
mopped = Counter()


def mop_l2(ctx: gspn.ActionContext):
    mopped[ctx.agent] += 1
    return None  # the net's rate decides when mopping ends


result = gspn.run(policy_plan, actions={"Mopping_L2": mop_l2}, until=2000.0, seed=7)
print(result.stopped, result.firings, "firings in", round(result.time, 1), "model seconds")
print("robots that mopped L2:", dict(mopped))

# %% [markdown]
# ## Plot: the expected robots in each activity over time, and the optimum's reward

# %%
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

times = np.linspace(0, 30, 31)
curve = gspn.analyze(policy_plan, transient=list(times), steady=False)
names = [p for p in curve.transient[0].places if p.startswith(("Mopping", "Vacuuming"))]
fig, ax = plt.subplots(figsize=(7, 4))
for name in names:
    i = curve.transient[0].places.index(name)
    ax.plot(times, [m.mean_tokens[i] for m in curve.transient], label=name)
ax.set_xlabel("model time")
ax.set_ylabel("E[robots]")
ax.set_title(f"home cleaning under the optimal policy (reward rate {best.value:.3f})")
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig("home_cleaning.png", dpi=100)
print("wrote home_cleaning.png")
