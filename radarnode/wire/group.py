"""Several radars on one bus: one node per radar, one scene time, one clock.

A scenario's ``radars:`` list (:attr:`radarnode.scene.scenario.Scenario.radars`) becomes a :class:`RadarGroup`:
one :class:`~radarnode.wire.node.RadarNode` per radar, each with its preset, mount, sensor ID (its CAN IDs shifted
by 0x10 × sensor ID, as the ARS 408 does) and seed (:func:`radarnode.radar.setup.radar_seed`), all computed at the
same scenario time and their frames sent one node after the other in each cycle, in the order of the list. The
group has the node's interface (``cycle``, ``receive``, ``withdraw``, ``missed_deadline``), so the runner, ``run``, ``node`` and
``log`` drive it unchanged. The bus is shared: each node keeps to its share of the bus-load budget
(``bus_load_limit`` divided by the number of radars). In closed loop the radars' scenes drive one ego: the
first radar's.

:func:`make_node` is what callers use: a plain node for one radar, a group for several.
"""

from __future__ import annotations

from collections import Counter

import can

from radarnode.radar.setup import radar_scenarios
from radarnode.scene.scenario import Scenario
from radarnode.wire.node import CycleOutput, EgoMotionSender, RadarNode


class RadarGroup:
    """The radars of one scenario as one node on the bus (see the module docstring)."""

    def __init__(self, scenario: Scenario, database=None, fidelity: str | None = None) -> None:
        self.scenario = scenario
        self.nodes = [RadarNode(sc, database, fidelity) for sc in radar_scenarios(scenario)]
        for node in self.nodes:
            node.bus_load_limit = node.bus_load_limit / len(self.nodes)
            # a RadarConfiguration may move a radar to a free sensor ID only
            node.taken_sensor_ids = lambda me=node: {n.config.sensor_id for n in self.nodes if n is not me}
        first = self.nodes[0]
        self.period_s, self.bitrate, self.preset = first.period_s, first.bitrate, first.preset
        self.fidelity = first.fidelity
        self.bus_load_limit = scenario.radar.bus_load_limit      # the whole bus's (each node keeps to its share)

    @property
    def sensor_ids(self) -> list[int]:
        """Each radar's sensor ID as it stands (a RadarConfiguration may move one to a free ID)."""
        return [n.config.sensor_id for n in self.nodes]

    @property
    def scene(self):
        """The first radar's scene (the ego and the actors; the others differ only in where the sensor sits)."""
        return self.nodes[0].scene

    @property
    def counters(self) -> Counter:
        """Every node's counters, summed (a frame the bus could not read is counted by the first node)."""
        return self._summed("counters")

    @property
    def saturated(self) -> Counter:
        """Every node's values saturated to their DBC signal's range, summed by signal (the first node's alone
        before)."""
        return self._summed("saturated")

    def _summed(self, name: str) -> Counter:
        total: Counter = Counter()
        for n in self.nodes:
            total.update(getattr(n, name))
        return total

    @property
    def config(self):
        return self.nodes[0].config

    def _share_ego(self) -> None:
        """One ego for every radar's scene: the first's (a closed loop drives it)."""
        lead = self.nodes[0].scene
        for n in self.nodes[1:]:
            n.scene._ego, n.scene.dynamic_ego = lead._ego, lead.dynamic_ego

    def receive(self, msg: can.Message, t_s: float) -> None:
        """Each node takes what is addressed to its sensor ID and ignores the rest."""
        for n in self.nodes:
            n.receive(msg, t_s)

    def cycle(self, t_s: float, timestamp: float | None = None) -> CycleOutput:
        """Every radar's cycle at ``t_s``; frames in list order, each node's after the previous node's on the wire.

        The output is the first radar's (frame, view, boundaries) with every node's messages and bits; ``outputs``
        holds each node's own :class:`CycleOutput`."""
        self._share_ego()
        t0 = t_s if timestamp is None else timestamp
        outs = []
        for n in self.nodes:
            outs.append(n.cycle(t_s, t0))
            t0 += outs[-1].bits / self.bitrate
        first = outs[0]
        out = CycleOutput(t_s, [m for o in outs for m in o.messages], first.frame, first.view,
                          sum(o.bits for o in outs), sum(o.objects_dropped for o in outs),
                          boundaries=first.boundaries)
        out.outputs = outs
        return out

    def withdraw(self, out: CycleOutput) -> None:
        for n, o in zip(self.nodes, out.outputs):
            n.withdraw(o)

    def missed_deadline(self, t_s: float, late_s: float, skipped: int = 0, computed: bool = True) -> None:
        for n in self.nodes:
            n.missed_deadline(t_s, late_s, skipped, computed)

    def warn_once(self, key: str, fmt: str, *args) -> None:
        self.nodes[0].warn_once(key, fmt, *args)

    def __getattr__(self, name):
        # what a caller reads of a node and the group does not define itself: the first radar's
        if name == "nodes":
            raise AttributeError(name)
        return getattr(self.nodes[0], name)


class GroupEgoMotion:
    """The vehicle's SpeedInformation 0x300 and YawRateInformation 0x301 for every radar (each at its sensor ID)."""

    def __init__(self, group: RadarGroup, database=None) -> None:
        self.senders = [EgoMotionSender(n.scene, n.config.sensor_id, database, n.config) for n in group.nodes]

    def frames(self, t_s: float, timestamp: float | None = None) -> list[can.Message]:
        return [m for s in self.senders for m in s.frames(t_s, timestamp)]


def make_node(scenario: Scenario, database=None, fidelity: str | None = None) -> RadarNode | RadarGroup:
    """The scenario's radar as a node: one :class:`RadarNode`, or a :class:`RadarGroup` for several radars."""
    if scenario.radars and len(scenario.radars) > 1:
        return RadarGroup(scenario, database, fidelity)
    if scenario.radars:
        return RadarNode(radar_scenarios(scenario)[0], database, fidelity)
    return RadarNode(scenario, database, fidelity)


def ego_motion_for(node: RadarNode | RadarGroup, database=None):
    """The vehicle's ego-motion sender for ``node``: one sensor ID, or every radar's of a group."""
    if isinstance(node, RadarGroup):
        return GroupEgoMotion(node, database)
    return EgoMotionSender(node.scene, node.config.sensor_id, database, node.config)


__all__ = ["GroupEgoMotion", "RadarGroup", "ego_motion_for", "make_node"]
