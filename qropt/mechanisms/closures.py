"""The closures a type's loop is written with (public re-export of ``qropt.kinematics.closures``).

Each takes the math namespace ``xp`` first and works on numbers, arrays, jets and CasADi expressions alike:
``circle_circle`` (RRR: two links meeting at a joint, on a branch sign), ``rod_to_line`` (RRP: a rod whose end
slides on a line y = h), ``pin_in_slot`` (RPR: the angle of a slotted lever), ``on_ray`` (a point along an
angle), and the transmission lines of a joint: ``joint_lines`` (coupler-follower), ``rod_lines`` (rod-slider)
and ``RIGHT_ANGLE`` (a block in a slot or a yoke)."""

import types as _types

from qropt.kinematics import closures as _source

# every public closure of qropt.kinematics.closures (those added later too), under the same names
__all__ = [
    k
    for k, v in vars(_source).items()
    if not k.startswith("_") and not isinstance(v, _types.ModuleType) and k != "annotations"
]
globals().update({k: getattr(_source, k) for k in __all__})
