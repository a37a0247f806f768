"""Limits that sweep outputs are judged against.

Allowable bending stress of a girth gear
----------------------------------------
The paper computes the tooth bending stress (Lewis, after Michalopoulos [11])
but gives no allowable.  kilnctl takes the allowable bending stress number of
through-hardened steel from ANSI/AGMA 2101-D04 (the metric edition of AGMA
2001-D04), Fig. 10 ("allowable bending stress number for through hardened
steel gears"):

* grade 1: ``sigma_FP = 0.533 HB + 88.3`` MPa
* grade 2: ``sigma_FP = 0.703 HB + 113`` MPa

with the Brinell hardness ``HB`` of the gear.  Large kiln girth gears are
steel castings, normalised and tempered to about 200-250 HB (AGMA 6014-A06
covers such gears); kilnctl assumes 220 HB and grade 1, which gives 205.6 MPa.

Two cautions.  The AGMA number is a limit for 10^7 load cycles at 99 %
reliability, to be compared with the AGMA bending stress, which includes the
geometry factor J (with the fillet stress concentration) and the overload,
dynamic, size and load-distribution factors; kilnctl's Lewis stress has none of
these, so it is lower than the AGMA stress and the margins it shows are
optimistic.  And a start-up is a rare peak, not 10^7 cycles: the AGMA number
is a conservative yardstick for it.  Treat the comparison as a ranking of
operating conditions, not as a rating of the gear.

>>> round(allowable_bending_stress() / 1e6, 1)
205.6
"""

from __future__ import annotations

import math

from ..errors import ParameterError

__all__ = ["allowable_bending_stress", "GIRTH_GEAR_HARDNESS_HB", "AGMA_BENDING_GRADES"]

#: assumed Brinell hardness of a cast-steel kiln girth gear (normalised and tempered, about 200-250 HB)
GIRTH_GEAR_HARDNESS_HB = 220.0

#: ANSI/AGMA 2101-D04 Fig. 10, through-hardened steel: sigma_FP = a*HB + b [MPa], by grade
AGMA_BENDING_GRADES = {1: (0.533, 88.3), 2: (0.703, 113.0)}


def allowable_bending_stress(hardness_hb: float = GIRTH_GEAR_HARDNESS_HB, grade: int = 1) -> float:
    """Return the AGMA allowable bending stress number of through-hardened steel [Pa].

    Parameters
    ----------
    hardness_hb : float, default 220
        Brinell hardness of the gear [HB]; the AGMA curves cover 150-400 HB.
    grade : {1, 2}, default 1
        AGMA material grade (1: ordinary quality control, the usual case for
        large castings).

    Returns
    -------
    float
        ``sigma_FP`` [Pa].

    Raises
    ------
    ParameterError
        A hardness outside 150-400 HB or an unknown grade.
    """
    if grade not in AGMA_BENDING_GRADES:
        raise ParameterError(f"grade = {grade!r}: AGMA 2101-D04 gives grades 1 and 2 for through-hardened steel")
    if isinstance(hardness_hb, bool) or not isinstance(hardness_hb, (int, float)) or not math.isfinite(hardness_hb) \
            or not 150.0 <= hardness_hb <= 400.0:
        raise ParameterError(f"hardness_hb = {hardness_hb!r}: the AGMA curves cover 150 to 400 HB")
    a, b = AGMA_BENDING_GRADES[grade]
    return (a * hardness_hb + b) * 1e6
