"""hapticd's client SDK for Python: sessions with a hapticd server, every object and field kind,
state as NumPy arrays, callbacks, events and lockstep stepping (docs/python.md).

    import hapticd
    with hapticd.Client(server_address="127.0.0.1:50051") as client:
        with client.add_wall(hapticd.WallSpec(normal=(0, 0, 1),
                                              impedance=hapticd.Impedance(stiffness=1000))):
            state = client.poll_state(timeout=0.1)
            print(state.position, state.force)

SI units throughout; positions, velocities and forces in the device's world frame W; durations in
seconds.
"""

from ._native import *  # noqa: F401,F403  (the bound SDK)
from . import _native
# `as`: re-exported, for type checkers.
from ._trajectory import Trajectory as Trajectory, record as record

# Classes print as hapticd.X, not hapticd._native.X.
for _name in dir(_native):
    _value = getattr(_native, _name)
    if isinstance(_value, type) and getattr(_value, "__module__", "") == "hapticd._native":
        try:
            _value.__module__ = "hapticd"
        except (AttributeError, TypeError):
            pass
del _name, _value

__all__ = [name for name in dir(_native) if not name.startswith("_")] + ["Trajectory", "record"]
