"""The cautions a diagnosis gives with its result: what weakens the evidence for what it selected.

- :func:`setup_cautions`: the setup's own model misses a channel's level (a unit or setup mismatch);
- :func:`skew_texts`: the measured speed matches the final model's best shifted in time (the logger's
  channels skewed, or a lag in the speed's sensor);
- :func:`effect_cautions`: per selected effect, a record shorter than its period or evidence weak once the
  residual's autocorrelation is allowed for (:func:`caution_texts`), a rival the record hardly tells apart
  (:func:`rival_texts`), values outside the usual range; an effect the backward check removed on the
  whitened BIC alone (:func:`removed_texts`); and base values far from the setup's (:func:`drift_texts`).

Used by :class:`~kilnctl.measure.diagnose.Diagnosis` to fill ``setup_cautions_`` and ``caveats_``.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import KilnctlError
from .compare import level_caution
from .effects import CATALOGUE
from .evidence import close_rival, within_noise
from .report import listed, unit_of as _unit
from .runner import CHANNELS, run_model

__all__ = ["setup_cautions", "effect_cautions", "drift_texts", "removed_texts", "rival_texts", "caution_texts",
           "skew_texts", "best_shift", "DRIFT_CHECKED", "SETUP_DRIFT", "SKEW_MAX_S", "SKEW_GAIN"]

#: the final model's base values checked against the setup's, and the fraction [-] beyond which a caution says
#: so (mu_s is left out: outside stick-slip only the breakaway shows it, and it is fitted loosely; with
#: stick-slip cycles in the final model it sets every breakaway and is checked too, see drift_texts)
DRIFT_CHECKED, SETUP_DRIFT = ("mu_c", "m_v", "J_v"), 0.25


def setup_cautions(m, params, exp, model: str = "macro") -> list[str]:
    """Cautions when the setup's own model, before any calibration, explains less of a channel than the
    record's mean (:func:`~kilnctl.measure.compare.level_caution`): a unit or setup
    mismatch, which the calibration papers over with implausible values and effects then stand in for (a
    current logged in per cent of its rating: the base calibrated to a fit of 0.3 %, then a kiln unbalance
    of 4.4e5 N m was selected).

    Parameters
    ----------
    m : Measurement
        The record.
    params : Parameters
        The setup (gains resolved).
    exp : Experiment
        The experiment of the record.
    model : str, default "macro"
        The base model.

    Returns
    -------
    list of str
        One text per channel whose level the setup's model misses.
    """
    try:
        run = run_model(params, m, exp, model=model)
    except KilnctlError:
        return []
    active = m.t >= exp.t0 - 1e-9
    texts = [level_caution(c, unit, m.channels[c][active], run.outputs[c]) for c, (_, unit) in CHANNELS.items()]
    return [f"the setup's model before calibration, {text} Until that is resolved, the diagnosis below is not "
            f"evidence of an effect." for text in texts if text is not None]


#: shifts of the measured speed against the model tried, up to this many seconds either way [s] ...
SKEW_MAX_S = 0.2
#: ... and the speed residual's RMS at the best shift must fall below this fraction of its RMS unshifted [-]
SKEW_GAIN = 0.7


def best_shift(t, measured, model, max_s: float = SKEW_MAX_S) -> tuple[float, float, float]:
    """The time shift of a measured signal against a model's that fits them best, in whole samples.

    Shift k (samples): the measured sample i is compared with the model's sample i - k, so k > 0 means the
    measured signal comes k samples *after* the model's.  All shifts are compared over the same samples.

    Parameters
    ----------
    t : ndarray
        Sample times [s] (an even grid; its median step is used).
    measured, model : ndarray
        The two signals at ``t``.
    max_s : float, default SKEW_MAX_S
        Largest shift tried either way [s].

    Returns
    -------
    (float, float, float)
        The best shift [s], the residual's RMS there and unshifted (in the signals' unit).
    """
    y, yhat = np.asarray(measured, float), np.asarray(model, float)
    dt = float(np.median(np.diff(t)))
    kmax = int(min(round(max_s / dt), (y.size - 1) // 4))
    if kmax < 1:
        return 0.0, math.nan, math.nan
    window = slice(kmax, y.size - kmax)
    rms = {k: float(np.sqrt(np.mean((y[window] - yhat[kmax - k: y.size - kmax - k]) ** 2)))
           for k in range(-kmax, kmax + 1)}
    k = min(rms, key=rms.get)
    return k * dt, rms[k], rms[0]


def skew_texts(comparison, selected=()) -> list[str]:
    """A caution when the measured speed matches the final model's far better shifted in time.

    The logger's channels may be skewed (the speed sampled or stamped later than the current: two loggers, a
    bus delay), or the speed's sensor may lag.  Neither is told from the record by the rounds: a skew is
    no effect of the plant, and the catalogue's ``speed_sensor_lag`` delays the speed the controller sees
    too.  Named when the best shift within :data:`SKEW_MAX_S` brings the speed residual's RMS below
    :data:`SKEW_GAIN` of its unshifted value (:func:`best_shift`).  (Red team 7: the speed logged 40 ms after
    the current, a ramp of 74 rpm/s: the speed 2.9 rpm behind the model's for the whole ramp, a compliance
    lost, nothing said.)

    Parameters
    ----------
    comparison : Comparison
        The final model's comparison with the record.
    selected : sequence of str
        The effects selected (named in the text).

    Returns
    -------
    list of str
        At most one caution.
    """
    ch = comparison.channels["speed_rpm"]
    shift, rms_best, rms_0 = best_shift(comparison.t, ch.measured, ch.model)
    if shift == 0.0 or not rms_best < SKEW_GAIN * rms_0:
        return []
    ms = 1000.0 * abs(shift)
    trails = shift > 0
    if "speed_sensor_lag" in selected:
        # kilnctl's lag delays the logged speed too: a filter only in the controller's path (the logger reading the
        # raw tachometer) leaves the measured speed ahead of the model's by about the lag (red team 9)
        lag = ("; the speed_sensor_lag selected does not account for it" if trails else
               "; or the speed_sensor_lag selected filters only the speed the controller sees, not the speed "
               "logged (kilnctl's lag delays both): then the record is not skewed")
    else:
        lag = ("; a lag of the speed's own sensor, which the controller sees too, is the catalogue's "
               "speed_sensor_lag (not selected)" if trails else "")
    return [f"the measured speed {'trails' if trails else 'leads'} the final model's by {ms:.0f} ms: shifted by "
            f"that much, its residual falls from {rms_0:.2g} to {rms_best:.2g} rpm RMS. The logger's channels may "
            f"be skewed (the speed logged {ms:.0f} ms {'after' if trails else 'before'} the current){lag}. "
            "Effects fitted to a skewed record stand in for the skew: align the channels if they are, and "
            "diagnose again"]


def effect_cautions(d, m, exp, params) -> list[str]:
    """Warnings about the selected effects of a fitted diagnosis ``d``: evidence weaker than the criteria
    suggest (:func:`caution_texts`), a rival the record hardly tells apart (:func:`rival_texts`), values outside
    the usual range, an effect removed on the whitened BIC alone (:func:`removed_texts`), a stiff compliance
    beside a second motor (:func:`mode_place_texts`), and base values far from the setup's
    (:func:`drift_texts`).

    Parameters
    ----------
    d : Diagnosis
        The fitted diagnosis (its rounds, selection and final calibration).
    m : Measurement
        The record.
    exp : Experiment
        The experiment of the record.
    params : Parameters
        The setup (gains resolved).

    Returns
    -------
    list of str
    """
    out = []
    span = float(m.t[-1] - exp.t0)
    added = getattr(d, "_added", None)
    if added is None:  # the round each effect was added in, found by its supported result
        added = {}
        for rnd in d.rounds_:
            for c in rnd:
                if c.supported and c.effect not in added:
                    added[c.effect] = c
    judged = []
    for name in d.selected_:
        r = added.get(name)
        if r is None:
            continue
        eff = CATALOGUE[name]
        period = eff.period(params, exp.omega_ref) if eff.period is not None else None
        # weak: neither the BIC with the coloured noise modelled nor a held-out gain of holdout_z standard
        # errors confirms the plain BIC (the whitened BIC alone misjudges an effect added to a model that
        # still misses much, e.g. the torque law whose misplaced breakaways it takes for noise)
        # ... unless the whitened BIC rises where the model with the effect fits within noise: the held-out
        # blocks share the fitting blocks' slow noise, and their z is then no confirmation (red team 14's C5: no
        # effect, a kiln unbalance at whitened +5.2 and held-out +21.3 % at 3.0 standard errors, no word)
        slow = r.delta_bic_corrected > 0.0 and within_noise(r.fit_percent)
        corrected = r.delta_bic_corrected if slow or not r.holdout_z > d.holdout_z else -math.inf
        said = caution_texts(name, span, period, eff.short_record_note, corrected, d.min_delta_bic)
        out += said or marginal_texts(name, r.delta_bic, r.holdout_gain, r.holdout_z, d.min_delta_bic,
                                      d.min_holdout_gain)
        if not any(r is a for a in judged):  # a pair added both its effects: its rivals are named once
            judged.append(r)
            out += rival_texts(d, r)
        out += form_rival_texts(d, name) + form_kept_texts(d, name) + form_also_texts(d, name)
        # the usual ranges scaled to this drive at the recorded set speed
        for note in eff.plausibility(d.final_calibration_.values_, params.replace(omega_ref=exp.omega_ref)):
            out.append(f"{name}: {note} (a value outside the usual range is reported, not refused)")
    return out + removed_texts(d) + mode_place_texts(d, params) + drift_texts(d, params)


def removed_texts(d) -> list[str]:
    """A caution for each effect the backward check removed on the BIC with the noise's correlation modelled
    alone, where the plain BIC and the held-out part favoured keeping it (dBIC below minus the threshold, a
    held-out gain above ``min_holdout_gain``): the selection kept is then one of two readings the record
    hardly tells apart.  On red team 17's E5 (an idle second rotor behind a fluid coupling) the second motor,
    added first, was removed beside a drag at whitened dBIC +14.3 though its plain dBIC was -383.4 and its
    held-out gain +17.4 % (1.5 standard errors), and the drag alone was reported with no word of it.

    Parameters
    ----------
    d : Diagnosis
        The fitted diagnosis (its removed effects, the backward check's judgements in ``checks_``, selection
        and thresholds).

    Returns
    -------
    list of str
    """
    out = []
    kept = listed(list(d.selected_)) if d.selected_ else "the base model"
    backward = [r for check, r in getattr(d, "checks_", ()) if check == "backward"]
    for r in getattr(d, "removed_", ()):
        if not any(r is b for b in backward):  # the swap and the final check tell their own story
            continue
        if r.delta_bic <= -d.min_delta_bic and r.holdout_gain > d.min_holdout_gain \
                and r.delta_bic_corrected > -d.min_delta_bic:
            z = f", {r.holdout_z:.1f} standard errors" if r.holdout_z is not None and math.isfinite(r.holdout_z) \
                else ""
            out.append(f"{r.effect} was removed in the backward check on the BIC with the noise's correlation "
                       f"modelled alone (whitened dBIC {r.delta_bic_corrected:+.1f}), though the plain BIC (dBIC "
                       f"{r.delta_bic:+.1f}) and the held-out part (gain {r.holdout_gain:+.1f} %{z}) favoured "
                       f"keeping it: on this record {kept} and {r.effect} change the current alike, and "
                       f"{r.effect} may be the cause. {_DECIDES}")
    return out


def mode_place_texts(d, params) -> list[str]:
    """A drive-train compliance selected with a second motor, stiffer than the usual range: where it may ring.

    The catalogue's compliance sits between the gearbox and the kiln.  A second motor coupled through a shaft of
    its own rings at a frequency set by that shaft and J_m2, and the compliance reproduces that ring only with a
    stiffness far above a drive train's: on red team 16's E3 and P1 (a second motor on a shaft of its own, 6 and
    9.6 Hz) both effects were selected, with k_po 13 and 42 times the top of the usual range.  The caution names
    the other place; it changes no selection.

    Parameters
    ----------
    d : Diagnosis
        The fitted diagnosis (its selection and final values).
    params : Parameters
        The setup.

    Returns
    -------
    list of str
        One caution, or none.
    """
    if not {"drivetrain_compliance", "second_motor"} <= set(d.selected_):
        return []
    values = d.final_calibration_.values_
    k_po = values.get("k_po")
    lo, hi = CATALOGUE["drivetrain_compliance"].usual("k_po", params)
    if k_po is None or not k_po > hi:
        return []
    return [f"drivetrain_compliance with second_motor: k_po = {k_po:.3g} N*m/rad, {k_po / hi:.2g} times the top of "
            f"the usual {lo:.2g}-{hi:.2g}. A second motor coupled through a shaft of its own rings at a frequency "
            "set by that shaft and J_m2, which the catalogue's compliance (between the gearbox and the kiln) "
            "matches only with a stiffness far above a drive train's: the ring may come from the second motor's "
            "shaft or coupling rather than the gear train."]


def drift_texts(d, params) -> list[str]:
    """A caution when the final model's friction, burden mass or kiln inertia lies more than
    :data:`SETUP_DRIFT` from the setup's value: the calibration may have made up for a difference the
    catalogue lacks (a motor constant falling with speed raises the current as a heavier burden does).
    Where the final model has stick-slip cycles (``d.stick_slip_``) the static friction mu_s is checked too.

    Parameters
    ----------
    d : Diagnosis
        The fitted diagnosis (its calibrated parameters and final calibration).
    params : Parameters
        The setup.

    Returns
    -------
    list of str
        At most one caution.
    """
    setup = {k: float(params[k]) for k in d.calibrate}
    final = d.final_calibration_.values_
    # with stick-slip cycles mu_s sets every breakaway: red team 19's P1 (a kiln that cycles under both laws, the
    # plant's law the torque law) ended with the paper law at mu_s 0.89 for the setup's 0.57, which imitated the
    # torque law's cycles, and nothing said so
    checked = DRIFT_CHECKED + (("mu_s",) if getattr(d, "stick_slip_", False) else ())
    far = [(k, final[k], setup[k]) for k in checked
           if k in final and k in setup and setup[k] > 0 and abs(final[k] / setup[k] - 1.0) > SETUP_DRIFT]
    if not far:
        return []

    def unit(k):
        u = _unit(k)
        return "" if u in ("-", "") else " " + u

    values = " and ".join(f"{k} = {v:.3g}{unit(k)}" for k, v, _ in far)
    sides = {"above" if v > s0 else "below" for _, v, s0 in far}
    if len(sides) == 1:  # "49 % and 36 % above"
        devs = " and ".join(f"{100 * abs(v / s0 - 1):.0f} %" for _, v, s0 in far) + f" {sides.pop()}"
    else:
        devs = " and ".join(f"{100 * abs(v / s0 - 1):.0f} % {'above' if v > s0 else 'below'}" for _, v, s0 in far)
    given = ", ".join(f"{s0:.3g}{unit(k)}" for k, _, s0 in far)
    verb = "lies" if len(far) == 1 else "lie"
    return [f"The final model's {values} {verb} {devs} the setup's ({given}). If the setup is right, the "
            f"calibration has made up for a difference the model lacks, which this diagnosis cannot name; if "
            f"it is not, correct the setup." + _motors_hint(far, params)]


def _motors_hint(far, params) -> str:
    """The drive of several motors that the burden's calibrated m_v and J_v point to, or "".

    With one motor's nameplate in the setup and N motors driving the kiln (one motor's current logged), the
    model's torque per logged ampere is 1/N of the drive's, and the calibration makes the burden's mass and
    inertia about 1/N of the setup's (red team 10's dual drive: 49 % and 48 % below).  Named when both lie
    within 15 % of 1/N for N = 2 to 4 and the setup does not already fold motors.
    """
    ratio = {k: v / s0 for k, v, s0 in far}
    if not {"m_v", "J_v"} <= set(ratio):
        return ""
    for n in (2, 3, 4):
        if all(abs(ratio[k] * n - 1.0) <= 0.15 for k in ("m_v", "J_v")):
            return (f" Both are near 1/{n} of the setup's: a kiln driven by {n} motors with one motor's current "
                    f"logged and one motor's nameplate in the setup gives exactly this (then write motors = {n} "
                    "in [motor]: kilnctl multiplies k_i, J_m and B_m by it).")
    return ""


#: how every rival caution ends: what would tell the effects apart
_DECIDES = "A record where they act differently (another ramp rate or set speed) decides."
#: what the rival caution says of rivals the swap check refitted in the winner's place
_NOT_BETTER = "did not fit better by every test"


def _swap_words(winner: str, rivals: list, tried: set) -> str:
    """The rival caution's clause on the swap check: which of ``rivals`` it refitted in the place of
    ``winner`` (``tried``: pairs (winner, rival), two rivals refitted together as a tuple of their names),
    each alone and two together, that did not fit better; empty when it refitted none."""
    alone = [c for c in rivals if (winner, c) in tried]
    together = [" and ".join(x) + " together" for w, x in sorted(tried, key=str)
                if w == winner and isinstance(x, tuple) and set(x) <= set(rivals)]
    if len(alone) == len(rivals) and len(rivals) > 1:
        who = "each in its place"
    elif len(alone) > 1:
        who = f"{listed(alone)}, each in its place,"
    elif alone:
        who = f"{alone[0]} in its place"
    elif together:
        return f", and {listed(together)} in its place {_NOT_BETTER}"
    else:
        return ""
    return f", and {who} {_NOT_BETTER}" + (f", nor {listed(together)}" if together else "")


def rival_texts(d, r) -> list[str]:
    """A caution when another candidate of the round whose winner was ``r`` was supported too and its dBIC,
    plain or whitened (:attr:`CandidateResult.delta_bic_corrected`), lies within the BIC threshold of the
    winner's (the rivals of the swap check, ``Diagnosis._swap``; the text says when that check refitted the
    rival in the winner's place and it did not fit better by every test): the record then hardly tells the two
    apart (a constant motor friction and a drag at nearly constant speed differ only during the ramp).  Rivals
    within the threshold by the whitened dBIC only share one caution when there are several (on red team 4's
    ovality record three of them: one story, told once).  A rival whose effects were all selected (in a later
    round) is none.  The winner has the lowest dBIC of the round's supported candidates (``diagnose._rank``),
    so a rival's gap is negative only for an effect the swap check put in the place of the round's winner
    (that story is told with the removed effects); such rivals, with a lower dBIC than ``r``, get no caution
    here.  A pair of which an effect was removed later has no rivals left to name.

    Parameters
    ----------
    d : Diagnosis
        The fitted diagnosis (its rounds, selection and BIC threshold).
    r : CandidateResult
        The result that added an effect.

    Returns
    -------
    list of str
    """
    if not set(r.effect.split("+")) <= set(d.selected_):
        # a pair of which the backward or swap check removed one: its rivals were rivals of what is gone (red
        # team 13's torque law + current limit, the limit removed, cautioned against the torque law + a motor
        # friction)
        return []
    rnd = next((rd for rd in d.rounds_ if any(c is r for c in rd)), [])
    kept = set(d.selected_) | set(r.effect.split("+"))
    tried = getattr(d, "swap_tried_", None) or set()
    out, whitened = [], []
    for c in rnd:
        if c is r or not c.supported or set(c.effect.split("+")) <= kept:
            continue
        gap = c.delta_bic - r.delta_bic
        if gap < 0.0 or not close_rival(r, c, d.min_delta_bic):
            continue
        if gap < d.min_delta_bic:
            out.append(f"{r.effect} was preferred to {c.effect} by a BIC difference of only {gap:.1f} (dBIC "
                       f"{r.delta_bic:+.1f} against {c.delta_bic:+.1f}; the threshold is {d.min_delta_bic:g}):"
                       f" on this record the two change the current alike, and either may be the cause. {_DECIDES}")
        else:  # within the threshold by the whitened dBIC only
            whitened.append(c)
    if len(whitened) == 1:
        c = whitened[0]
        wgap = c.delta_bic_corrected - r.delta_bic_corrected
        by = f"the two differ by only {wgap:.1f}" if wgap >= 0.0 else f"{c.effect} is the better by {-wgap:.1f}"
        out.append(f"{r.effect} was preferred to {c.effect} by BIC (dBIC {r.delta_bic:+.1f} against "
                   f"{c.delta_bic:+.1f}), but with the noise's correlation modelled {by} (whitened dBIC "
                   f"{r.delta_bic_corrected:+.1f} against {c.delta_bic_corrected:+.1f}; the threshold is "
                   f"{d.min_delta_bic:g})"
                   + _swap_words(r.effect, [c.effect], tried)
                   + f": on this record the two change the current alike, and either may be the cause. {_DECIDES}")
    elif whitened:  # one caution for all of them: the same story told once
        names = listed([c.effect for c in whitened])
        out.append(f"{r.effect} was preferred by BIC (dBIC {r.delta_bic:+.1f}) to {names} (dBIC "
                   f"{listed([f'{c.delta_bic:+.1f}' for c in whitened])}), but with the noise's correlation "
                   f"modelled each of them is about as good or better (whitened dBIC {r.delta_bic_corrected:+.1f} "
                   f"against {listed([f'{c.delta_bic_corrected:+.1f}' for c in whitened])}; the threshold is "
                   f"{d.min_delta_bic:g})"
                   + _swap_words(r.effect, [c.effect for c in whitened], tried)
                   + f": on this record they change the current much as {r.effect} does, and any of them may be "
                   f"the cause. {_DECIDES}")
    return out


def form_rival_texts(d, effect: str) -> list[str]:
    """A caution when a selected effect, kept in its own form, was refitted in another of its forms that tells
    another story (:attr:`~kilnctl.model.catalogue.Form.alike`) and fitted about as well: its dBIC against the
    effect's own form below twice the BIC threshold.  On red team 12's R15 a roller friction falling to nothing
    at the set speed was selected as a constant motor friction with a burden 5 % light; the falling form, with
    a burden near the plant's, fitted as well (dBIC -43.8, whitened +11.1, held-out +0.6 %) but not better by
    every test.  Effects selected after the friction are named as possibly the rest of the form's story.

    Parameters
    ----------
    d : Diagnosis
        The fitted diagnosis (its forms tried, ``form_results_``, and the forms kept, ``forms_``).
    effect : str
        A selected effect.

    Returns
    -------
    list of str
    """
    if effect in (getattr(d, "forms_", None) or {}):
        return []
    entries = [e for e in getattr(d, "form_results_", None) or []
               if e[0] == effect and not e[3] and set(e[4]) <= set(d.selected_)]
    out = []
    for form in CATALOGUE[effect].forms:
        tried = [e for e in entries if e[1] == form.name]
        if not tried or form.alike is None:
            continue
        ev = tried[-1][2]
        cal = ev.calibration
        # about as well: within twice the BIC threshold, as for marginal evidence (red team 14's F14: the falling
        # refit at dBIC +11.9 with the plant's burden, the constant one 2.9 % light and nothing said)
        if cal is None or not ev.delta_bic < 2.0 * d.min_delta_bic:
            continue
        # against the final model's values: the constant friction and the burden the report gives
        story = form.alike(cal.values_, d.final_calibration_.values_)
        if story is None:
            continue
        # the effects added after it may be the rest of the form's story (red team 14's F4, B2: a friction
        # flat to half speed and falling after, taken as a constant one, then a second motor for the ramp)
        later = d.selected_[d.selected_.index(effect) + 1:]
        rest = (f" {listed(later)}, added after it, may stand in for the rest of that story: select again "
                f"without {'it' if len(later) == 1 else 'them'} (--candidates) to see.") if later else ""
        out.append(f"{effect}: in its {form.name} form it fits this record about as well ({story}; dBIC "
                   f"{ev.delta_bic:+.1f} against its own form, {ev.delta_bic_corrected:+.1f} with the noise's "
                   f"correlation modelled, held-out gain {ev.holdout_gain:+.1f} %): the record hardly tells the "
                   f"two apart.{rest} {_DECIDES}")
    return out


def form_kept_texts(d, effect: str) -> list[str]:
    """A caution when a selected effect was kept in another of its forms, which tells another story
    (:attr:`~kilnctl.model.catalogue.Form.alike`), in a model with stick-slip cycles, on a held-out gain
    within ``d.holdout_z`` standard errors.

    With stick-slip in the model the cost is rugged: each refit stops in one of many nearby valleys, and which
    one decides a difference of a few per cent of the cost.  On red team 15's E8 (a constant motor friction of
    150 N*m, the torque friction law) the constant form's refit ended 3.2 % above the cost that the same form
    reached from the plant's values (715.8 against 692.9; starts between the two ended between), while the
    falling form, with one more parameter to escape by, ended 4.0 % below it (686.9): it was kept at dBIC
    -276.8 against the constant form (whitened -147.0), held-out +1.3 % at 1.3 standard errors, with the burden
    2.2 % heavy and nothing said.  The BIC then measures the valleys the fits reached as much as the record; a
    held-out gain beyond ``d.holdout_z`` standard errors is the evidence the caution asks for.  Without
    stick-slip the BIC stands on its own (red team 14's falling frictions: kept at 1.0-1.7 standard errors,
    rightly).

    Parameters
    ----------
    d : Diagnosis
        The fitted diagnosis (``forms_``, ``form_results_``, ``stick_slip_``, ``holdout_z``).
    effect : str
        A selected effect.

    Returns
    -------
    list of str
    """
    form_name = (getattr(d, "forms_", None) or {}).get(effect)
    if form_name is None or not getattr(d, "stick_slip_", False):
        return []
    kept = [e for e in getattr(d, "form_results_", None) or []
            if e[0] == effect and e[1] == form_name and e[3]]
    form = CATALOGUE[effect].form(form_name)
    if not kept or form is None or form.alike is None:
        return []
    ev, own = kept[-1][2], kept[-1][5]
    if ev.holdout_z > d.holdout_z:
        return []
    # the form's story at the final values, against the own form's refit in the round that kept the form
    story = form.alike(d.final_calibration_.values_, own)
    if story is None:
        return []
    return [f"{effect}: kept in its {form_name} form ({story} in its own form), which fitted better (dBIC "
            f"{ev.delta_bic:+.1f} against its own form, {ev.delta_bic_corrected:+.1f} with the noise's "
            f"correlation modelled), but the held-out part does not bear that out (gain {ev.holdout_gain:+.1f} %, "
            f"{ev.holdout_z:.1f} standard errors): with stick-slip cycles in the model each refit stops in one of "
            f"many nearby valleys of the cost, and which one decides a difference of this size. Either form may "
            f"be right. {_DECIDES}"]


def form_also_texts(d, effect: str) -> list[str]:
    """A caution when a selected effect is in a form whose values a change outside the catalogue imitates on one
    start-up (:attr:`~kilnctl.model.catalogue.Form.also`): red team 21's X1, a motor field weakened at the ramp
    start and restored with 1.6 s, was selected as a motor friction falling by 100 % at the set speed.

    Parameters
    ----------
    d : Diagnosis
        The fitted diagnosis (``forms_``, ``final_calibration_``).
    effect : str
        A selected effect.

    Returns
    -------
    list of str
    """
    form_name = (getattr(d, "forms_", None) or {}).get(effect)
    form = CATALOGUE[effect].form(form_name) if form_name is not None else None
    if form is None or form.also is None:
        return []
    text = form.also(d.final_calibration_.values_)
    return [f"{effect} in its {form_name} form: {text}. {_DECIDES}"] if text else []


def marginal_texts(effect: str, delta_bic: float, holdout_gain: float, holdout_z: float, min_delta_bic: float,
                   min_holdout_gain: float) -> list[str]:
    """A caution when an effect was selected on evidence just past the BIC threshold (less than twice it) that
    the held-out part does not bear out (a gain below the threshold and below one standard error).

    Red team 13's dfilt_A (no effect; the plant's derivative acts through a 0.1 s filter, 0.5 A rms) took a
    speed-sensor lag of 2.8 ms so, at dBIC -10.6, held-out +0.3 % (0.4 standard errors), without a word; on the
    benchmark a true compliance three times stiffer than usual was selected on the same kind of evidence
    (dBIC -16.2, held-out -0.1 %).

    Parameters
    ----------
    effect : str
        The selected effect.
    delta_bic, holdout_gain, holdout_z : float
        Its evidence when it was added: dBIC [-], held-out gain [%], and that gain in standard errors [-].
    min_delta_bic, min_holdout_gain : float
        The diagnosis' thresholds [-], [%].

    Returns
    -------
    list of str
        At most one caution.
    """
    if not (-2.0 * min_delta_bic < delta_bic < 0.0) or holdout_gain > min_holdout_gain or holdout_z >= 1.0:
        return []
    return [f"{effect}: the evidence is marginal: BIC falls by {-delta_bic:.1f}, within twice the threshold of "
            f"{min_delta_bic:g}, and the held-out part is predicted no better ({holdout_gain:+.1f} %, "
            f"{holdout_z:+.1f} standard errors). A small difference the catalogue lacks (in the controller: a "
            f"filtered derivative, a sampling delay) can draw the same; a record with larger or sharper changes "
            f"(a faster ramp, a load step) tells."]


def caution_texts(effect: str, span_s: float, period_s: float | None, short_record_note: str,
                  delta_bic_corrected: float, min_delta_bic: float) -> list[str]:
    """The cautions a user reads about one selected effect (empty when there is nothing to say).

    Two things weaken the evidence for a selected effect: a record shorter
    than the period of its signature (then only part of a cycle is seen, which
    other causes also make) and a BIC gain that misses the threshold once the
    residual's autocorrelation is allowed for.

    Parameters
    ----------
    effect : str
        Catalogue name of the effect.
    span_s : float
        Length of the record from the start of the experiment [s].
    period_s : float or None
        Period of the effect's signature [s]; None for an effect without one
        (then no short-record caution).
    short_record_note : str
        What else makes the signature in a record shorter than a period.
    delta_bic_corrected : float
        delta BIC corrected for residual autocorrelation [-].
    min_delta_bic : float
        The BIC threshold of the diagnosis [-] (positive).

    Returns
    -------
    list of str
        At most one caution.
    """
    weak = not (delta_bic_corrected < -min_delta_bic)
    short = period_s is not None and math.isfinite(period_s) and period_s > 0 and span_s < period_s
    if short:
        text = (f"{effect} was selected on a record of {span_s:.0f} s, {span_s / period_s:.2f} of its period "
                f"({period_s:.0f} s)")
        text += (f": there it is {short_record_note}" if short_record_note else
                 ": only part of a cycle is seen, which other causes can also produce")
        if weak:
            text += (f"; its evidence is weak once the residual's autocorrelation is allowed for "
                     f"(whitened dBIC {delta_bic_corrected:+.1f})")
        return [text + ". A record longer than one period tells them apart."]
    if weak:
        return [f"{effect}: the evidence is weak once the residual's autocorrelation is allowed for "
                f"(whitened dBIC {delta_bic_corrected:+.1f} against the threshold {-min_delta_bic:g}); small "
                "effects (a few-millisecond sensor lag, a stiff drive train) are often like this, but so is an "
                "effect that fits slow noise."]
    return []
