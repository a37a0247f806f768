"""Synthetic "measured" records from a plant with hidden effects, for tests and benchmarks.

A record is simulated on a plant that has the hidden effects (magnitudes
drawn from the catalogue's plausible ranges), two or three base parameters
off by +-5 %, and white plus coloured (first-order autoregressive)
measurement noise, all from one seed.  The plant is kilnctl's own model:
a diagnosis that works here has passed a necessary test, not a sufficient
one (measured kilns differ in ways no generator anticipates).
"""

from __future__ import annotations

import math

import numpy as np

from ..params import Parameters
from .effects import CATALOGUE, effect_components
from .io import Measurement

__all__ = ["make_record", "MISMATCH_POOL", "DEFAULT_GAINS"]

#: base parameters that may be off in the synthetic plant
MISMATCH_POOL = ("mu_c", "m_v", "J_o", "J_v", "mu_s")
#: controller gains of the synthetic experiments (stated in their setup, as a real test would)
DEFAULT_GAINS = {"gains": "given", "k_p": 2.0, "k_I": 5.0, "k_D": 0.01}


def _sampled(resp, t):
    tt = np.asarray(resp.t, float)
    rev = tt[::-1]
    _, idx = np.unique(rev, return_index=True)
    keep = tt.size - 1 - idx
    return {k: np.interp(t, tt[keep], np.asarray(resp.outputs[k], float)[keep])
            for k in ("i_a", "speed_rpm", "speed_ref_rpm")}


def _ar1(rng, n, sigma, tau, dt):
    """Stationary AR(1) noise with standard deviation sigma and correlation time tau [s]."""
    if sigma <= 0:
        return np.zeros(n)
    phi = math.exp(-dt / tau) if tau > 0 else 0.0
    w = rng.standard_normal(n) * sigma * math.sqrt(1 - phi ** 2)
    x = np.empty(n)
    x[0] = rng.standard_normal() * sigma
    for k in range(1, n):
        x[k] = phi * x[k - 1] + w[k]
    return x


def make_record(hidden=(), *, seed: int = 0, params: Parameters | None = None, magnitudes: dict | None = None,
                mismatch=None, mismatch_frac: float = 0.05, t_end: float = 30.0, fs: float = 50.0,
                white=(4.0, 0.3), coloured=(4.0, 0.3), tau_noise: float = 0.4):
    """Simulate a "measured" start-up of a plant with hidden effects.

    Parameters
    ----------
    hidden : sequence of str
        Catalogue effects the plant has (the model under test does not).
    seed : int, default 0
        Seed of every random draw.
    params : Parameters, optional
        Setup the user would state (default: Table 1 with the gains of
        :data:`DEFAULT_GAINS`); the plant deviates from it.
    magnitudes : dict, optional
        Effect parameters to use instead of drawing them [units of each];
        for ``current_limit``, ``I_max`` may be given in A.
    mismatch : sequence of str, optional
        Base parameters to put off by +-``mismatch_frac`` (default: two or
        three drawn from :data:`MISMATCH_POOL`).
    mismatch_frac : float, default 0.05
        Relative mismatch [-].
    t_end : float, default 30.0
        Record length [s].
    fs : float, default 50.0
        Sampling frequency [Hz].
    white : (float, float), default (4.0, 0.3)
        White noise standard deviation on current [A] and speed [rpm].
    coloured : (float, float), default (4.0, 0.3)
        Coloured (AR(1)) noise standard deviation on current [A] and speed [rpm].
    tau_noise : float, default 0.4
        Correlation time of the coloured noise [s].

    Returns
    -------
    measurement : Measurement
        The record (with ``speed_ref_rpm``).
    truth : dict
        ``hidden``, ``magnitudes`` (effect parameters), ``mismatch``
        (parameter -> plant value), ``plant`` (the plant's parameter values
        that differ from the setup), ``model``, ``noise``.
    """
    from ..simulate import simulate

    setup = Parameters(DEFAULT_GAINS) if params is None else params
    rng = np.random.default_rng(seed)
    hidden = tuple(hidden)
    if mismatch is None:
        k = int(rng.integers(2, 4))
        mismatch = tuple(rng.choice(MISMATCH_POOL, size=k, replace=False))
    changes = {}
    for name in mismatch:
        changes[name] = float(setup[name]) * (1.0 + mismatch_frac * rng.choice([-1.0, 1.0]))
    if "mu_c" in changes or "mu_s" in changes:
        mu_c, mu_s = changes.get("mu_c", setup.mu_c), changes.get("mu_s", setup.mu_s)
        if mu_c > mu_s:
            changes["mu_s"] = mu_c
    model = "micro" if any(CATALOGUE[h].model == "micro" for h in hidden) else "macro"
    mags = dict(magnitudes or {})
    for h in hidden:
        for name, (lo, hi) in CATALOGUE[h].plausible.items():
            if name in mags:
                continue
            if h == "current_limit":
                continue
            if name.startswith("phi"):
                mags[name] = float(rng.uniform(lo, hi))
            elif lo > 0 and hi / lo > 3:
                mags[name] = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
            else:
                mags[name] = float(rng.uniform(lo, hi))
    comps, plant = effect_components(hidden, setup.replace(**changes), model=model)
    plant = plant.replace(**{k: v for k, v in mags.items() if k != "I_max"})
    if "current_limit" in hidden and "I_max" not in mags:
        free = simulate(plant, model, t_end=t_end, effects=comps, remove=("current_limit",))
        lo, hi = CATALOGUE["current_limit"].plausible["I_max"]
        mags["I_max"] = float(rng.uniform(lo, hi) * np.max(np.abs(free.outputs["i_a"])))
    if "I_max" in mags:
        plant = plant.replace(I_max=mags["I_max"])
    dt = 1.0 / fs
    t = np.arange(0.0, t_end, dt)
    resp = simulate(plant, model, t_end=t_end, effects=comps)
    y = _sampled(resp, t)
    cur = y["i_a"] + white[0] * rng.standard_normal(t.size) + _ar1(rng, t.size, coloured[0], tau_noise, dt)
    spd = y["speed_rpm"] + white[1] * rng.standard_normal(t.size) + _ar1(rng, t.size, coloured[1], tau_noise, dt)
    m = Measurement.from_arrays(t, cur, spd, y["speed_ref_rpm"], source=f"synthetic(seed={seed})", params=setup)
    diff = {k: v for k, v in plant.as_dict().items() if v != setup[k]}
    truth = {"hidden": list(hidden), "magnitudes": mags, "mismatch": {k: changes[k] for k in changes},
             "plant": diff, "model": model,
             "noise": {"white": list(white), "coloured": list(coloured), "tau_s": tau_noise}}
    return m, truth


#: what the shipped example record hides (named here and in docs/tutorial_diagnose.md, never in the data file)
EXAMPLE_HIDDEN = ("second_motor",)


def write_example(folder, *, seed: int = 1994) -> tuple:
    """Write the shipped example: ``example_record.csv`` and ``example_setup.toml``.

    A 40 s start-up at 50 Hz of a plant with the paper's second, electrically
    isolated motor (J_m2 = 21.5 kg m^2), burden mass and Coulomb friction
    off by 5 %, white plus coloured noise, and 1 s of pre-trigger samples at
    rest (the ramp starts at t = 1 s).

    Parameters
    ----------
    folder : path-like
        Destination folder; existing files are refused.
    seed : int, default 1994
        Seed of the noise.

    Returns
    -------
    (Path, Path)
        The record and the setup file.
    """
    from pathlib import Path

    from ..response import write_atomic

    folder = Path(folder)
    setup = Parameters(DEFAULT_GAINS)
    m, _ = make_record(EXAMPLE_HIDDEN, seed=seed, params=setup, magnitudes={"J_m2": 21.5},
                       mismatch=("m_v", "mu_c"), t_end=40.0, fs=50.0)
    rng = np.random.default_rng(seed + 1)
    pre = np.arange(-50, 0) / 50.0
    t = np.concatenate([pre, m.t]) + 1.0
    cur = np.concatenate([4.0 * rng.standard_normal(pre.size), m.current])
    spd = np.concatenate([0.3 * rng.standard_normal(pre.size), m.speed])
    ref = np.concatenate([np.zeros(pre.size), m.speed_ref])
    rec = Measurement.from_arrays(t, cur, spd, ref, params=setup)
    csv_path, toml_path = folder / "example_record.csv", folder / "example_setup.toml"
    body = rec.to_csv()
    header = ("# kilnctl example record: a start-up of the kiln drive, logged at 50 Hz\n"
              "# current_A: armature current of motor 1; speed_rpm: motor speed; speed_ref_rpm: drive reference\n")
    if csv_path.exists() or toml_path.exists():
        raise FileExistsError(f"{folder}: example files exist; remove them first")
    write_atomic(csv_path, header + body)
    write_atomic(toml_path, (
        "# Setup of the example experiment (kilnctl parameter file; see docs/measurements.md)\n"
        "# The controller gains are those the drive ran with; the rest is the paper's Table 1.\n"
        "[controller]\ngains = \"given\"\nk_p = 2.0\nk_I = 5.0\nk_D = 0.01\n\n"
        "[drive]\nramp_rate = 74.0\nomega_ref = 500.0\n\n"
        "[kiln]\nm_v = 580000.0\nmu_c = 0.4\nmu_s = 0.51\n\n"
        "[measurement]\ncalibrate = [\"mu_c\", \"mu_s\", \"m_v\"]\n"))
    return csv_path, toml_path
