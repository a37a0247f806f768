"""Fig. 4 of the paper: motor current of the macro model for several burden friction coefficients.

The paper prints only mu3 = (mu_c, mu_s) = (0.4, 0.51), the pair that fitted
the measured current best (620 A simulated, 650 A measured, settling after
15 s and oscillating).  Its mu1, mu2, mu4 are not printed: this study brackets
mu3 with mu_c = 0.30, 0.35, 0.40, 0.45 at the same gap mu_s - mu_c = 0.11,
runs them with both friction laws, and finds the mu_c that gives 620 A.

Run: ``python studies/fig04_friction.py`` (writes studies/out/fig04_friction/).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from kilnctl import Parameters
from kilnctl.report import PaperTable, oscillation, settle_time
from kilnctl.simulate import simulate
from kilnctl.sweep import Study
from kilnctl.sweep.space import Space

STUDY = "fig04_friction"
OUT = Path(__file__).parent / "out" / STUDY
T_END = 40.0  # s
MU_GAP = 0.11  # mu_s - mu_c of the paper's mu3
MU_C = (0.30, 0.35, 0.40, 0.45)  # mu1..mu4 (mu3 = 0.40 as printed; the others chosen around it)
I_PAPER, I_MEASURED = 620.0, 650.0  # A, paper Fig. 4 and Fig. 5


def sliding_current(p: Parameters) -> float:
    """Motor current with the burden sliding at tan(psi*) = mu_c*R/L at the set speed (hand calculation).

    Parameters
    ----------
    p : Parameters
        Kiln, burden and motor parameters.

    Returns
    -------
    float
        Armature current [A]: kiln torque (burden plus bearing, eq. 17) over n*k_i, plus the
        motor's viscous loss B_m*omega_m/k_i.
    """
    psi = math.atan(p.mu_c * p.R / p.L)
    torque_kiln = p.m_v * p.g * p.L * math.sin(psi) + p.T_brg
    return torque_kiln / (p.n * p.k_i) + p.B_m * (p.omega_ref / p.K_fb) / p.k_i


def mu_c_for_current(p: Parameters, current: float) -> float:
    """Kinetic coefficient whose sliding equilibrium draws a given current (inverse of sliding_current).

    Parameters
    ----------
    p : Parameters
        Kiln, burden and motor parameters (mu_c is ignored).
    current : float
        Steady armature current [A].

    Returns
    -------
    float
        mu_c [-].
    """
    torque_kiln = (current - p.B_m * (p.omega_ref / p.K_fb) / p.k_i) * p.n * p.k_i - p.T_brg
    return math.tan(math.asin(torque_kiln / (p.m_v * p.g * p.L))) * p.L / p.R


class Pairs(Space):
    """Points listed one by one: Fig. 4 varies mu_c and mu_s together (a Grid takes every combination).

    Parameters
    ----------
    **columns : sequence
        Values of each variable at each point, all of the same length.
    """

    method = "points"

    def __init__(self, **columns):
        self.names = tuple(columns)
        self.columns = {k: np.array(v, dtype=object if isinstance(v[0], str) else float) for k, v in columns.items()}

    def __len__(self) -> int:
        return len(self.columns[self.names[0]])

    def samples(self) -> dict:
        """Return the values of each variable at each point."""
        return dict(self.columns)

    def describe(self) -> dict:
        """Return the values of each variable as text."""
        return {k: "values " + ", ".join(f"{x:g}" if not isinstance(x, str) else x for x in v)
                for k, v in self.columns.items()}


# --- outputs of the sweep: measures of one macro-model run --------------------------------------
def final(r) -> float:
    """Mean current of the last 5 s [A]."""
    return r.window_mean("i_a", 5.0)


def mean20(r) -> float:
    """Mean current of the last 20 s [A]."""
    return r.window_mean("i_a", 20.0)


def settle(r) -> float:
    """Time after which the current stays within 5 % of its final value [s] (NaN: never)."""
    f = final(r)
    t = settle_time(r.t, r["i_a"], 0.05 * f, f)
    return np.nan if t is None else t


def ptp(r) -> float:
    """Peak-to-peak current of the last 15 s [A]."""
    return oscillation(r.t, r["i_a"], T_END - 15.0)[0]


def freq(r) -> float:
    """Frequency of the current oscillation of the last 15 s [Hz] (NaN: none)."""
    f = oscillation(r.t, r["i_a"], T_END - 15.0)[1]
    return np.nan if f is None else f


def peak(r) -> float:
    """Largest current [A]."""
    return float(np.max(r["i_a"]))


OUTPUTS = {f.__name__: f for f in (final, mean20, settle, ptp, freq, peak)}


def main(out: Path = OUT) -> PaperTable:
    """Run the study, write its figure and table, print the table.

    Parameters
    ----------
    out : path-like, optional
        Output folder (default ``studies/out/fig04_friction``).

    Returns
    -------
    PaperTable
        The comparison with the paper.
    """
    table1 = Parameters()
    mu_fit = mu_c_for_current(table1, I_PAPER)
    # mu1..mu4 with both friction laws, then the pair fitted to 620 A; the gains designed for Table 1 throughout
    keys = [(law, mu) for law in ("paper", "torque") for mu in MU_C] + [("paper", "fit")]
    space = Pairs(friction_law=[law for law, _ in keys],
                  mu_c=[mu_fit if mu == "fit" else mu for _, mu in keys],
                  mu_s=[mu_fit + MU_GAP if mu == "fit" else round(mu + MU_GAP, 3) for _, mu in keys])
    study = Study(space, OUTPUTS, model="macro", t_end=T_END, base=table1, name=STUDY)
    table = study.run(executor="serial", progress=False).table
    m = {k: row._asdict() for k, row in zip(keys, table.itertuples())}
    mf = m.pop(("paper", "fit"))
    base = study.controlled_base()  # Table 1 with the designed gains
    runs = {k: simulate(p, "macro", t_end=T_END)  # the currents of the figure: the sweep keeps only the outputs
            for k, p in zip(keys, study.parameter_sets())}
    fit = runs.pop(("paper", "fit"))

    # --- figure -------------------------------------------------------------------------
    fig = Figure(figsize=(11, 8.5))
    axes = fig.subplots(2, 1, sharex=True)
    colors = {mu: c for mu, c in zip(MU_C, ("#1b9e77", "#7570b3", "#d95f02", "#e7298a"))}
    for ax, law, title in ((axes[0], "paper", "(a) printed friction law (breakaway by forces, eq. 3)"),
                           (axes[1], "torque", "(b) torque-consistent friction law")):
        for k, mu in enumerate(MU_C):
            r = runs[law, mu]
            ax.plot(r.t, r["i_a"], color=colors[mu], lw=2.2 if mu == 0.40 else 1.3,
                    label=f"mu{k + 1}: mu_c = {mu:.2f}, mu_s = {mu + MU_GAP:.2f}")
        if law == "paper":
            ax.plot(fit.t, fit["i_a"], color="k", ls="--", lw=1.3,
                    label=f"fitted to 620 A: mu_c = {mu_fit:.3f}, mu_s = {mu_fit + MU_GAP:.3f}")
        for y, txt, dy, va in ((I_PAPER, "620 A: paper, simulated with mu3", -10, "top"),
                               (I_MEASURED, "650 A: measured (Fig. 5)", 10, "bottom")):
            ax.axhline(y, color="0.35", ls=":", lw=1)
            ax.text(0.3, y + dy, txt, color="0.25", fontsize=8, va=va)
        ax.axvline(15.0, color="0.6", lw=0.8)
        ax.set_ylabel("motor current [A]")
        ax.set_title(title, loc="left", fontsize=10)
        ax.set_ylim(0, 1150)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="lower right", fontsize=8, ncol=1)
    axes[1].text(15.2, 40, "15 s (paper: settled)", color="0.4", fontsize=8)
    axes[1].set_xlabel("time [s]")
    fig.suptitle("Fig. 4 reproduced: macro model start-up, designed PID gains, Table 1 kiln", fontsize=12)
    fig.tight_layout()
    Path(out).mkdir(parents=True, exist_ok=True)
    fig.savefig(Path(out) / "fig04_friction.png", dpi=110)

    # --- table ----------------------------------------------------------------------------
    tab = PaperTable(STUDY, "macro-model motor current for friction pairs around mu3 = (0.40, 0.51)")
    m3 = m["paper", 0.40]
    p3 = base.replace(mu_c=0.4)
    psi3 = math.atan(p3.mu_c * p3.R / p3.L)
    T3 = p3.m_v * p3.g * p3.L * math.sin(psi3)
    tab.add("final current, mu3, printed law", "620 A simulated, 650 A measured",
            f"{m3['final']:.0f} A (hand calculation {sliding_current(p3):.0f} A)", "differs",
            f"Table 1 fixes it: the burden slides at tan psi = mu_c R/L ({math.degrees(psi3):.1f} deg), kiln torque "
            f"{T3 / 1e6:.2f} MN m, {T3 / p3.n / 1e3:.2f} kN m at the motor, / k_i = {p3.k_i} N m/A "
            f"-> {sliding_current(p3):.0f} A (NOTES.md, worked steady state). The drive dynamics do not change "
            "a steady state")
    tab.add("mu_c that gives 620 A (mu_s = mu_c + 0.11)", "mu_c = 0.40",
            f"mu_c = {mu_fit:.3f} (simulated: {mf['final']:.0f} A)", "differs",
            "fitted as the paper did (current), with Table 1 as printed. If the sliding equilibrium were "
            f"tan psi = mu_c (arms L and R ignored, as in eq. 3) mu_c = 0.40 would give "
            f"{_force_reading_current(base):.0f} A; a hypothesis, not a fact")
    tab.add("current settled (within 5 % of final), mu3", "after 15 s",
            f"after {m3['settle']:.1f} s", "agrees" if abs(m3["settle"] - 15.0) < 2.0 else "differs",
            "kilnctl: the burden is carried up (stick, then Filippov 'held') and slides from "
            f"{_first(runs['paper', 0.40], 'held', 'slip_pos'):.1f} s on")
    w_exact = math.sqrt(base.m_v * base.g * math.hypot(base.L, 0.4 * base.R) / base.J_v) / (2 * math.pi)
    tab.add("oscillation after settling, mu3", "oscillates (eq. 25: undamped, about a fixed offset)",
            f"{m3['ptp']:.0f} A peak-to-peak at {m3['freq']:.3f} Hz, undamped", "agrees",
            f"burden sliding oscillation about psi*: exact linearisation of eq. 22 {w_exact:.3f} Hz; "
            f"eq. 25 sqrt(C1/J_v) = {math.sqrt(base.m_v * base.g * base.L / base.J_v) / (2 * math.pi):.3f} Hz")
    tab.add("final current mu1..mu4, printed law", "not printed (mu3 fits best)",
            ", ".join(f"{m['paper', mu]['final']:.0f}" for mu in MU_C) + " A", "not in paper",
            "rises with mu_c as m_v g L sin(atan(mu_c R/L)). mu_s plays no part here: with the printed law the "
            "breakaway at tan psi = mu_s < mu_c R/L only enters 'held', and sliding starts at tan psi = mu_c R/L")
    rt, mt = runs["torque", 0.40], m["torque", 0.40]
    brk = [e.t for e in rt.events if e.kind == "breakaway"]
    tl = list(rt.t)
    psi_brk = np.degrees([rt["psi"][tl.index(e.t)] for e in rt.events if e.kind == "breakaway"])
    psi_rest = np.degrees([rt["psi"][tl.index(e.t)] for e in rt.events if e.kind == "restick"])
    tab.add("torque-consistent law, mu3", "not studied",
            f"stick-slip cycles {np.min(rt['i_a'][rt.t > 20]):.0f}-{mt['peak']:.0f} A every "
            f"{np.mean(np.diff(brk)):.2f} s, mean {mt['mean20']:.0f} A (last 20 s); never settles", "not in paper",
            f"breakaway at tan psi = mu_s R/L ({np.mean(psi_brk):.1f} deg), slides back to {np.mean(psi_rest):.1f} deg "
            "and re-sticks; Fig. 4's small oscillation about a plateau looks like the printed law's sliding, not "
            "these cycles")
    tab.write(out)
    print(tab.to_text())
    return tab


def _force_reading_current(p: Parameters) -> float:
    """Current [A] if the burden slid at tan psi = mu_c (forces compared, arms ignored), mu_c = 0.4."""
    psi = math.atan(0.4)
    return (p.m_v * p.g * p.L * math.sin(psi) + p.T_brg) / (p.n * p.k_i) + p.B_m * (p.omega_ref / p.K_fb) / p.k_i


def _first(r, from_mode: str, to_mode: str) -> float:
    """Time [s] of the first burden switch from_mode -> to_mode."""
    return next(e.t for e in r.events if e.component == "burden" and e.from_mode == from_mode
                and e.to_mode == to_mode)


if __name__ == "__main__":
    main()
