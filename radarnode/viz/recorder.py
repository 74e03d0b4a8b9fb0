"""A ``can.Listener`` that turns a run into Foxglove topics, written to MCAP or served live.

:class:`FoxgloveRecorder` is given CAN frames the way python-can's file writers are
(``on_message_received``): every frame goes to ``/can/frames`` as it is, and to its own
:class:`~radarnode.consumer.assembler.CycleAssembler`, so the objects, clusters, road boundaries and the
ECU's AccStatus/FcwStatus it publishes are what the wire carried, decoded the way any consumer decodes
them. What no frame carries comes from the scenario on topics of its own: the ego (``/tf``, ``/ego``,
``/ego/state``), the ground truth (``/ground_truth/…``) and, at the signal level, the range–Doppler map. A
node being run hands over each cycle (:meth:`FoxgloveRecorder.on_node_cycle`); for a log on disk the truth is
evaluated at the time of each decoded cycle (:meth:`FoxgloveRecorder.attach_scene`).

Sinks are foxglove-sdk's, bound to the recorder's own ``foxglove.Context`` (so two recorders in one process
never share a channel): :meth:`FoxgloveRecorder.open_mcap` writes an MCAP file,
:meth:`FoxgloveRecorder.serve` speaks Foxglove's WebSocket protocol. A channel is created with its first
message, so a file holds exactly the topics that had something to say.
"""

from __future__ import annotations

import collections
import logging
import math
import threading
from collections.abc import Callable

import can

from radarnode.consumer.assembler import ClusterCycle, CycleAssembler, ObjectCycle
from radarnode.errors import ConfigError
from radarnode.viz import TOPICS, stamp_ok
from radarnode.viz import messages as M
from radarnode.wire import ids
from radarnode.wire.dbc import load_bus_database, load_database, load_own_database

logger = logging.getLogger(__name__)

#: the range of the ground-truth road lines ahead of the ego, m
ROAD_RANGE_M = 250.0


def foxglove_module():
    """``foxglove`` (foxglove-sdk), or a ConfigError saying how to install it."""
    try:
        import foxglove
    except ImportError:
        raise ConfigError("Foxglove output needs foxglove-sdk: pip install 'radarnode[foxglove]'") from None
    return foxglove


def _ns(t_s: float) -> int:
    return max(int(round(float(t_s) * 1e9)), 0)


#: a decoded vehicle speed further than this from the scene's ego is another run's (the frame's resolution: 0.02 m/s)
SPEED_TOLERANCE_MPS = 1.0


class FoxgloveRecorder(can.Listener):
    """Decode CAN frames into Foxglove topics (:data:`radarnode.viz.TOPICS`) on its own ``foxglove.Context``.

    Parameters
    ----------
    sensor_id : int
        The radar whose frames are decoded (the ECU's are decoded whatever the sensor).
    """

    def __init__(self, sensor_id: int = 0) -> None:
        fg = foxglove_module()
        self._fg = fg
        self.context = fg.Context()
        self.sensor_id = sensor_id
        self.counts: collections.Counter = collections.Counter()    # messages published, by topic
        self._lock = threading.RLock()
        self._channels: dict[str, object] = {}
        self._mcap = None
        self._server = None
        self._closed = False
        self._assembler = CycleAssembler(sensor_id=sensor_id, on_cycle=self._on_decoded_cycle, maxsize=1)
        self._names = {m.frame_id: m.name for m in load_bus_database().messages}
        own = load_own_database()
        self._ecu = {ids.ACC_STATUS: ("/ecu/acc", own.get_message_by_frame_id(ids.ACC_STATUS)),
                     ids.FCW_STATUS: ("/ecu/fcw", own.get_message_by_frame_id(ids.FCW_STATUS))}
        self._json_schemas = {"/can/frames": M.CAN_FRAME_SCHEMA, "/ego/state": M.EGO_STATE_SCHEMA,
                              **{topic: M.signal_schema(message) for topic, message in self._ecu.values()}}
        self._sides = {ids.own_id(ids.ROAD_BOUNDARY_LEFT, sensor_id): "left",
                       ids.own_id(ids.ROAD_BOUNDARY_RIGHT, sensor_id): "right"}
        prob = load_database().get_message_by_name("Obj_2_Quality").get_signal_by_name("Obj_ProbOfExist")
        self._prob_names = dict(prob.choices or {})
        self._mount_z_m = 0.5
        self._scene = None
        self._node = None
        self._start_time_s = 0.0
        self._truth_from_cycles = False
        #: decoded cycles given the scene's truth, and those outside the scenario's run (time − start time before 0
        #: or after its end), with the first such cycle's time: a log and a start time that do not go together
        self.truth_cycles, self.cycles_outside_run, self.first_outside_s = 0, 0, None
        #: of those cycles, the ones where the vehicle speed decoded from the log (SpeedInformation) was compared with
        #: the scene's ego, those that differ by more than SPEED_TOLERANCE_MPS, and the largest difference: a log
        #: given another run's scenario (:func:`radarnode.cli.export.cmd` warns)
        self.speed_compared, self.speed_off, self.speed_worst_mps = 0, 0, 0.0
        #: frames left out because their time is none a Foxglove message can carry (:func:`stamp_ok`): NaN, ±inf,
        #: before 0 or from 2**32 s on (a damaged or hand-made log), with the first such time
        self.frames_without_time, self.first_bad_time = 0, None

    # --- sinks --------------------------------------------------------------------------------------------
    def open_mcap(self, path: str, *, metadata: dict[str, str] | None = None,
                  attachments: list[tuple[str, str, bytes]] | None = None) -> None:
        """Record to the MCAP file ``path`` (overwritten), with ``metadata`` (a ``radarnode`` metadata record)
        and ``attachments`` ((name, media type, data), e.g. the scenario file)."""
        self._mcap = self._fg.open_mcap(path, allow_overwrite=True, context=self.context)
        if metadata:
            self._mcap.write_metadata("radarnode", {k: str(v) for k, v in metadata.items()})
        for name, media_type, data in attachments or ():
            self._mcap.attach(log_time=0, create_time=0, name=name, media_type=media_type, data=data)

    def serve(self, host: str = "127.0.0.1", port: int = 8765, name: str = "radarnode"):
        """Serve the topics live over Foxglove's WebSocket protocol; returns the server (``.port`` is the port
        bound, useful with ``port=0``).

        Every topic's channel is created first, so a client is told all of them when it connects: a channel
        created while a client subscribes can lose that subscription in foxglove-sdk ("Unknown channel ID").
        """
        for topic in TOPICS:
            self._channel(topic)
        self._server = self._fg.start_server(name=name, host=host, port=port, context=self.context)
        return self._server

    # --- the scenario ---------------------------------------------------------------------------------------
    def attach_node(self, node) -> None:
        """Take ground truth, ego and (signal level) the range–Doppler map from ``node`` (a RadarNode) at every
        :meth:`on_node_cycle`."""
        self._node = node
        self._scene = node.scene
        self._mount_z_m = float(node.scenario.radar.mount.z_m)
        from radarnode.radar.models import SignalModel
        for model in (node.model, getattr(node.model, "signal", None)):
            if isinstance(model, SignalModel):
                model.keep_rd = True

    def attach_scene(self, scene, start_time_s: float = 0.0) -> None:
        """Publish the truth of ``scene`` (a :class:`radarnode.scene.world.Scene`) with every decoded cycle, at
        scenario time = the cycle's timestamp − ``start_time_s`` (for a log on disk)."""
        self._scene = scene
        self._mount_z_m = float(scene.scenario.radar.mount.z_m)
        self._start_time_s = float(start_time_s)
        self._truth_from_cycles = True

    # --- can.Listener -----------------------------------------------------------------------------------------
    def on_message_received(self, msg: can.Message) -> None:
        with self._lock:
            if self._closed:
                return
            if not stamp_ok(msg.timestamp):
                # nowhere on the time line of the MCAP file or the live view: left out and counted (a NaN time of a
                # damaged log ended the export with a traceback: an independent tester's finding)
                self.frames_without_time += 1
                if self.first_bad_time is None:
                    self.first_bad_time = msg.timestamp
                return
            # an FD frame on one of the bus's IDs is not that message (the ARS 408's bus is classical CAN), nor is an
            # error frame whose class has the bits of one: no name
            name = "" if msg.is_extended_id or msg.is_fd or msg.is_error_frame \
                else self._names.get(msg.arbitration_id, "")
            self._publish("/can/frames", msg.timestamp, lambda: M.can_frame(msg, name))
            stats = self._assembler.stats
            before = (stats.boundary_frames, stats.ecu_frames)
            self._assembler.on_message_received(msg)     # cycles come back through _on_decoded_cycle
            if msg.is_extended_id:
                return
            if stats.boundary_frames != before[0] and msg.arbitration_id in self._sides:
                side = self._sides[msg.arbitration_id]
                b = self._assembler.road_boundaries[side]
                self._publish("/radar/road_boundaries", msg.timestamp,
                              lambda: M.boundary_update(side, b, msg.timestamp, mount_z_m=self._mount_z_m))
            if stats.ecu_frames != before[1] and msg.arbitration_id in self._ecu:
                topic, message = self._ecu[msg.arbitration_id]
                values = self._assembler.ecu_status[message.name]
                self._publish(topic, msg.timestamp, lambda: M.signal_record(message, values, msg.timestamp))

    def on_error(self, exc: Exception) -> None:
        logger.warning("bus error in the Foxglove recorder: %s", exc)

    def stop(self) -> None:
        self.close()

    def close(self) -> None:
        """Deliver the cycle being assembled, then finish the MCAP file and stop the server (idempotent)."""
        with self._lock:
            if self._closed:
                return
            self._assembler.flush()
            self._closed = True
            mcap, self._mcap = self._mcap, None
            server, self._server = self._server, None
        if mcap is not None:
            mcap.close()
        if server is not None:
            server.stop()

    # --- what the node and the assembler hand over ---------------------------------------------------------------
    def on_node_cycle(self, out) -> None:
        """The node sent cycle ``out`` (a :class:`radarnode.wire.node.CycleOutput`): publish the ego, the truth
        and, at the signal level, the range–Doppler map at the time of its first frame."""
        node = self._node
        if node is None:
            return
        t_wire = out.messages[0].timestamp if out.messages else out.t_s
        with self._lock:
            if self._closed:
                return
            self._publish_scene(out.t_s, t_wire, out.view)
            info = getattr(node.model, "info", None)
            rd = getattr(info, "rd_power", None)
            if rd is not None:
                preset, built = node.preset, {}

                def image():          # built only when someone listens (a live view may have no client)
                    built["image"], built["scales"] = M.range_doppler_image(
                        rd, preset.range_resolution_m, min(preset.max_range_m, node.config.max_distance_m), t_wire)
                    return built["image"]
                self._publish("/radar/range_doppler", t_wire, image)
                if built:
                    self._publish("/radar/range_doppler/annotations", t_wire,
                                  lambda: M.range_doppler_annotations(built["scales"], preset.doppler_bin_mps, t_wire))

    def _on_decoded_cycle(self, cycle: ObjectCycle | ClusterCycle) -> None:
        t = cycle.timestamp
        if isinstance(cycle, ObjectCycle):
            self._publish("/radar/objects", t, lambda: M.objects_update(cycle.objects, t, mount_z_m=self._mount_z_m,
                                                                        prob_names=self._prob_names))
        else:
            self._publish("/radar/clusters", t, lambda: M.clusters_cloud(cycle.clusters, t,
                                                                         mount_z_m=self._mount_z_m))
        if self._truth_from_cycles and self._scene is not None:
            # the node computed cycle k at k periods; its header goes out a little later (after the ego's frames
            # and RadarState), so the cycle's scenario time is the grid point just before the header
            sc = self._scene.scenario
            k = math.floor((t - self._start_time_s) / sc.period_s + 0.25)
            if 0 <= k <= int(sc.duration_s / sc.period_s + 1e-9):
                t_s = k * sc.period_s
                self._publish_scene(t_s, t, self._scene.view(t_s))
                self.truth_cycles += 1
            else:
                self.cycles_outside_run += 1
                if self.first_outside_s is None:
                    self.first_outside_s = t

    def _publish_scene(self, t_s: float, t_wire: float, view) -> None:
        """Ego and ground truth at scenario time ``t_s``, stamped ``t_wire`` (the time base of the frames)."""
        scene = self._scene
        sc = scene.scenario
        ego = scene.ego_state(t_s)
        wire_v, wire_yaw = self._assembler.ego_speed_mps, self._assembler.ego_yaw_rate_dps
        if wire_v is not None:
            diff = abs(wire_v - ego.speed_mps)
            self.speed_compared += 1
            self.speed_off += diff > SPEED_TOLERANCE_MPS
            self.speed_worst_mps = max(self.speed_worst_mps, diff)
        self._publish("/tf", t_wire, lambda: M.transforms(ego, sc.radar.mount, t_wire))
        self._publish("/ego", t_wire, lambda: M.ego_update(sc.ego.length_m, sc.ego.width_m, t_wire))
        self._publish("/ego/state", t_wire, lambda: {
            "timestamp": float(t_wire), "speed_mps": ego.speed_mps, "accel_mps2": ego.accel_mps2,
            "yaw_rate_dps": math.degrees(ego.yaw_rate_rps), "x_m": ego.x_m, "y_m": ego.y_m,
            "heading_deg": math.degrees(ego.heading_rad), "wire_speed_mps": wire_v, "wire_yaw_rate_dps": wire_yaw})
        self._publish("/ground_truth/actors", t_wire, lambda: M.truth_update(scene, view, t_wire,
                                                                             mount_z_m=self._mount_z_m))
        self._publish("/ground_truth/road", t_wire, lambda: M.road_update(scene, t_s, t_wire, range_m=ROAD_RANGE_M,
                                                                          mount_z_m=self._mount_z_m))

    # --- channels ------------------------------------------------------------------------------------------------
    def _channel(self, topic: str):
        """The channel of ``topic`` (created on first use, with the schema of :data:`TOPICS`)."""
        ch = self._channels.get(topic)
        if ch is None:
            schema_name = TOPICS[topic][0]
            if schema_name.startswith("foxglove."):
                from foxglove import channels
                ch = getattr(channels, f"{schema_name.split('.', 1)[1]}Channel")(topic, context=self.context)
            else:
                ch = self._fg.Channel(topic, schema=self._json_schemas[topic], context=self.context)
            self._channels[topic] = ch
        return ch

    def _publish(self, topic: str, t_s: float, build: Callable[[], object]) -> None:
        """Build and log one message on ``topic`` at ``t_s`` — skipped (not even built) while a live channel has
        no subscriber."""
        ch = self._channel(topic)
        if not ch.has_sinks():
            return
        ch.log(build(), log_time=_ns(t_s))
        self.counts[topic] += 1
