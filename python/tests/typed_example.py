"""A typed program against hapticd for test_stubs.py: `mypy --strict` checks it against the
package's stubs (python/hapticd/_native.pyi) and the test then runs it on a lockstep server, so
what the stubs accept is also what the module does."""

from __future__ import annotations

from typing import List, Optional, Tuple

import numpy as np
import numpy.typing as npt

import hapticd


def press_on_a_sphere(server_address: str) -> Tuple[float, npt.NDArray[np.float64], List[str]]:
    """The simulated hand pushes the tool down with 2 N onto a sphere whose top is 20 mm below
    it, for one second. Returns the sphere's largest stable stiffness, the force of the last
    sample (the sphere holding the hand: ≈ (0, 0, 2) N) and the kinds of the events seen."""
    config = hapticd.ClientConfig(server_address=server_address, client_name="typed-example",
                                  heartbeat_period=0.02)
    events: List[str] = []

    def on_event(event: hapticd.Event) -> None:
        events.append(event.kind.name)

    with hapticd.Client(config) as client:
        client.on_event(on_event)
        spec = hapticd.SphereSpec(center=(0.0, 0.0, -0.1), radius=0.1,
                                  impedance=hapticd.Impedance(stiffness=1000.0, damping=1.0))
        spec.center = np.array([0.0, 0.0, -0.1])
        with client.add_sphere(spec) as sphere:
            report: hapticd.StabilityReport = sphere.stability
            client.set_operator(hapticd.OperatorInput.push((0.0, 0.0, -2.0)))
            run: hapticd.Trajectory = hapticd.record(client, 1000, every=10)
            state: Optional[hapticd.State] = client.wait_for_tick(int(run.tick[-1]), timeout=1.0)
            if state is None:
                raise TimeoutError("no sample of the last tick")
            assert state.flags & hapticd.StateFlag.FORCE_FAULT == 0
        try:
            client.add_sphere(hapticd.SphereSpec(radius=-1.0))
        except hapticd.InvalidArgumentError as error:
            assert error.code == hapticd.ErrorCode.INVALID_ARGUMENT
        client.on_event(None)
    return report.max_stable_stiffness, run.force[-1], events
