"""The radar node: configuration state, ego-motion input, and one cycle's frames.

:class:`RadarNode` owns the radar model and turns each cycle into the ordered
list of ARS 408-21 frames: RadarState 0x201 at start, once a second and after
every configuration change; VersionID 0x700 once a second; the answers to
configuration (FilterState 0x203 + 0x204 after a FilterCfg 0x202; CollDetState
0x408 + one CollDetRegionState 0x402 per region after a CollDetCfg 0x400 or
CollDetRegionCfg 0x401, and every cycle while collision detection is on); then
either the object list (0x60A, all 0x60B, all 0x60C if SendQuality, all 0x60D
if SendExtInfo, all 0x60E while collision detection is on, one object order in
every group) or the cluster list (0x600, all 0x701, all 0x702 if SendQuality);
CollDetRelayCtrl 0x008 while collision detection and CtrlRelay are on; then the
node's own road-boundary frames. Configuration received before a cycle is
computed applies to it, and a burst of configuration messages is answered once,
with the state in force. The filters and collision detection are
:mod:`radarnode.wire.config`. It keeps a bus-load budget: when a cycle would not
fit, the lowest-priority objects are dropped, counted, and warned about once.
Pacing and I/O are the runner's job (``radarnode.wire.runner``).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import can
import numpy as np

from radarnode.errors import WireError
from radarnode.perception.boundaries import Boundary, RoadBoundaryEstimator
from radarnode.perception.types import MEAS_NEW, RadarFrame
from radarnode.radar import presets
from radarnode.radar.setup import radar_config, radar_path
from radarnode.radar.levels import check_level, make_model
from radarnode.radar.object_model import MAX_OBJECTS, RuntimeConfig
from radarnode.scene.scenario import Scenario
from radarnode.scene.world import Scene, SensorView
from radarnode.schema import Source
from radarnode.wire import ars408 as P
from radarnode.wire import ids
from radarnode.wire.busload import STANDARD_BITS_NOMINAL, STANDARD_BITS_WORST, frame_bits
from radarnode.wire.codec import MessageCodec
from radarnode.wire.config import MAX_OBJECT_ID, TYPE_CLUSTER, TYPE_NAMES, TYPE_OBJECT, CollisionDetection, ListFilters
from radarnode.wire.dbc import load_database, load_own_database
from radarnode.wire.e2e import E2EProtector

logger = logging.getLogger(__name__)

MOTION_TIMEOUT_S = 1.0     # ego-motion input older than this is "missing"
MIN_MAX_DISTANCE_M = presets.MIN_MAX_DISTANCE_M    # the smallest RadarCfg_MaxDistance accepted
# what the node receives (base IDs, shifted by 0x10 x SensorID on the bus)
RX_IDS = (P.RADAR_CFG, P.FILTER_CFG, P.SPEED_INFO, P.YAW_RATE_INFO, P.COLL_DET_CFG, P.COLL_DET_REGION_CFG)
FILTER_CFG_MIN_DLC = 5     # FilterCfg: 5 bytes in Continental's DBC for sensor 1, 8 in sensor 0's
STATUS_PERIOD_S = 1.0      # RadarState and VersionID


@dataclass
class NodeConfig:
    """The sensor configuration in force (what RadarState 0x201 echoes)."""

    output_type: int = P.OUTPUT_OBJECTS
    send_quality: bool = True
    send_ext_info: bool = True
    max_distance_m: float = 250.0
    sort_index: int = 1
    radar_power: int = 0
    sensor_id: int = 0
    rcs_threshold: int = 0
    ctrl_relay: bool = False
    nvm_write_ok: bool = False


@dataclass
class CycleOutput:
    """Everything one cycle produced: frames in bus order, the frame, and ground truth."""

    t_s: float
    messages: list[can.Message]
    frame: RadarFrame
    view: SensorView
    bits: int
    objects_dropped: int = 0
    counters: dict = field(default_factory=dict)
    boundaries: tuple[Boundary, Boundary] | None = None
    #: how many of ``messages`` lead up to and include the cycle's header (the status frames before it)
    lead: int = 0


class RadarNode:
    """An ARS 408-21 compatible node driven by a scenario.

    Parameters
    ----------
    scenario : Scenario
    database : cantools Database, optional
        Defaults to the project's ``dbc/ars408.dbc``.
    fidelity : str, optional
        ``object``, ``detection``, ``signal`` or ``auto``; default: the scenario's.
    """

    def __init__(self, scenario: Scenario, database=None, fidelity: str | None = None) -> None:
        self.scenario = scenario
        self.db = database if database is not None else load_database()
        setup = scenario.radar
        self.preset = radar_config(scenario).preset
        self.period_s = scenario.period_s
        self.bitrate = setup.bitrate
        self.bus_load_limit = setup.bus_load_limit
        max_distance, problem = presets.max_distance(self.preset, setup.max_distance_m)
        if problem is not None:
            field = f"{radar_path(scenario)}.max_distance_m"
            raise Source.of_lines(scenario.source, scenario.lines).error(
                field, f"field '{field}': value {max_distance:g} is not allowed; expected {problem}")
        self.config = NodeConfig(
            output_type=P.OUTPUT_CODES[setup.output], send_quality=setup.send_quality,
            send_ext_info=setup.send_ext_info, max_distance_m=max_distance,
            sort_index=P.SORT_CODES[setup.sort_index], radar_power=setup.radar_power, sensor_id=setup.sensor_id)
        self.scene = Scene(scenario)
        self.fidelity = fidelity or scenario.fidelity
        check_level(self.fidelity, radar_config(scenario).signal, scenario)       # file:line of the field
        self.model = make_model(self.fidelity, self.scene, self.preset, np.random.default_rng(scenario.seed),
                                radar_config(scenario).signal, clusters_wanted=setup.output == "clusters")
        self.counters: Counter = Counter()
        self.saturated: Counter = Counter()
        self.codecs = {m.frame_id: MessageCodec(m, self.saturated) for m in self.db.messages
                       if not m.is_multiplexed()}
        self.own_codecs = {m.frame_id: MessageCodec(m, self.saturated) for m in load_own_database().messages}
        self._rx_messages = {base: self.db.get_message_by_frame_id(base) for base in RX_IDS}
        self._rx_length = {base: m.length for base, m in self._rx_messages.items()}
        self._rx_last: dict[int, tuple[bytes, dict]] = {}     # 0x300/0x301: the last payload and its signals
        #: the filters (FilterCfg 0x202) and collision detection (0x400/0x401) in force
        self.filters = ListFilters(self.db)
        self.coll_det = CollisionDetection(self.db)
        self._reply_filters = False      # FilterState 0x203/0x204 due with the next cycle
        self._reply_coll_det = False     # CollDetState 0x408 / CollDetRegionState 0x402 due with the next cycle
        self._rx_t = 0.0                 # scenario time given to the frame being received
        # when the model's tracker first reported each object ID (NaN: not reported last cycle), for Lifetime
        self._born = np.full(MAX_OBJECT_ID + 1, np.nan)
        self._born_any = False          # whether _born holds a time (an object was listed last cycle)
        wants = setup.road_boundaries
        if wants is None:
            g = scenario.road.guardrails
            wants = g.left_offset_m is not None or g.right_offset_m is not None or any(
                a.object_class == "guardrail" for a in scenario.actors)
        self.boundaries = RoadBoundaryEstimator() if wants else None
        self._e2e = E2EProtector()
        self.last_boundaries: tuple[Boundary, Boundary] | None = None
        self._pipe = None                  # a BoundaryPipeline that computes the boundaries (defer_boundaries)
        self._runtime: tuple | None = None    # the last RuntimeConfig and what it was made from (_runtime_config)
        self._wire_id_tables: dict[int, dict[int, int]] = {}   # CAN IDs on the wire, per sensor ID (_wire_id)
        self._pipe_index = 0
        self._blank: list = [None, None, {}]   # blank boundary payloads for the pipeline (defer_boundaries)
        self._pipe_rows = False                 # the clusters go to the pipeline as block rows (defer_boundaries)
        self._last_t: float | None = None
        self._speed: tuple[float, float] | None = None    # (value m/s signed, time received)
        self._yaw: tuple[float, float] | None = None      # (deg/s, time received)
        self._next_status_s = 0.0
        self._status_now = True
        self._meas_counter = 0
        self._fault_until_s = -math.inf   # RadarState_Temporary_Error is set until then (a missed deadline)
        self._warned: set[str] = set()
        #: the sensor IDs the other radars of this node's group hold (:class:`radarnode.wire.group.RadarGroup` sets
        #: it): a RadarConfiguration that asks for one of them is refused
        self.taken_sensor_ids: Callable[[], set[int]] = set

    # --- input ------------------------------------------------------------

    def receive(self, msg: can.Message, t_s: float) -> None:
        """Handle a received frame: configuration (0x200, 0x202, 0x400, 0x401) and ego motion (0x300, 0x301).

        Frames of other IDs (another sensor's, the node's own traffic) are not for this node and ignored.
        What is for it but cannot be used is dropped and counted, never raised: error frames
        (``rx_error_frames``), remote frames (``rx_remote_frames``), CAN FD frames (``rx_fd_frames``: a classical
        CAN node never takes them), a DLC shorter than the message's (``rx_wrong_dlc``; a longer one is taken, its
        first bytes read, and counted in ``rx_padded``), a signal
        outside its DBC range (``rx_out_of_range``, ``rx_invalid_speed_direction``); configuration values the
        sensor refuses are counted in ``config_rejected`` (see :meth:`_refuse`).
        """
        self._rx_t = t_s
        if msg.is_error_frame:
            self.counters["rx_error_frames"] += 1
            return
        if msg.is_extended_id:
            return                       # a 29-bit ID is another message altogether
        base = msg.arbitration_id - 0x10 * self.config.sensor_id
        if base not in RX_IDS:
            return
        if msg.is_remote_frame:
            self.counters["rx_remote_frames"] += 1
            return
        if msg.is_fd:
            # the ARS 408 is a classical CAN node: its controller never takes a CAN FD frame (a 64-byte FD frame on
            # 0x300 was read as a padded speed: an independent tester's finding)
            self.counters["rx_fd_frames"] += 1
            return
        length = self._rx_length[base]
        data = bytes(msg.data)
        if base == P.FILTER_CFG and FILTER_CFG_MIN_DLC <= len(data) < length:
            # Continental's DBC for sensor 1 gives FilterCfg 5 bytes (every signal lies in them), sensor 0's 8:
            # a tool built on either is understood (the missing bytes are zero, as in an 8-byte frame)
            data = data + bytes(length - len(data))
        elif len(data) > length:
            # padded to a longer DLC (bench tools and gateways that send every frame with 8 bytes): its signals are
            # in the first bytes, as AUTOSAR's DLC check takes a frame at least as long as configured (the 2-byte
            # 0x300/0x301 padded to 8 were dropped, and the node ran with "speed missing")
            self.counters["rx_padded"] += 1
            data = data[:length]
        if len(data) != length:
            self.counters["rx_wrong_dlc"] += 1
            self._warn_once(f"dlc{base}", "frame 0x%X has DLC %d, expected %d; dropped (counted in rx_wrong_dlc, "
                            "warned once)", msg.arbitration_id, len(msg.data), length)
            return
        if base == P.FILTER_CFG:         # multiplexed: decoded by cantools
            self.counters["rx_filter_cfg"] += 1
            f, why = self.filters.configure(data)
            if why is not None:
                self._refuse("filter", "FilterCfg: %s; the filter table is unchanged", why)
            elif f is not None:
                logger.debug("filter %s %s: active=%s [%g, %g]", TYPE_NAMES[f.type], f.name, f.active, f.min, f.max)
            self._reply_filters = True
            return
        # one frame: cantools' compiled decoder (the vectorised codec pays numpy's per-call cost for every signal);
        # the vehicle sends the same 0x300/0x301 bytes cycle after cycle while its speed and yaw rate hold: those
        # are decoded once
        last = self._rx_last.get(base)
        if last is not None and last[0] == data:
            values = last[1]
        else:
            values = self._rx_messages[base].decode(data, decode_choices=False, scaling=True)
            if base in (P.SPEED_INFO, P.YAW_RATE_INFO):
                self._rx_last[base] = (data, values)
        if base == P.SPEED_INFO:
            direction = int(values["RadarDevice_SpeedDirection"])
            if direction == 3:
                self.counters["rx_invalid_speed_direction"] += 1
                return
            sign = -1.0 if direction == 2 else 1.0
            self._speed = (sign * values["RadarDevice_Speed"], t_s)
            self.counters["rx_speed"] += 1
        elif base == P.YAW_RATE_INFO:
            yaw = values["RadarDevice_YawRate"]
            if not -327.68 - 1e-9 <= yaw <= 327.66 + 1e-9:       # raw 0xFFFF: beyond the DBC's range
                self.counters["rx_out_of_range"] += 1
                self._warn_once("yawrange", "YawRateInformation: %.2f deg/s is outside -327.68..327.66; dropped "
                                "(counted in rx_out_of_range, warned once)", yaw)
                return
            self._yaw = (yaw, t_s)
            self.counters["rx_yaw_rate"] += 1
        elif base == P.COLL_DET_CFG:
            self.counters["rx_coll_det_cfg"] += 1
            self.coll_det.configure(values)
            self._reply_coll_det = True
        elif base == P.COLL_DET_REGION_CFG:
            self.counters["rx_coll_det_region_cfg"] += 1
            why = self.coll_det.configure_region(values)
            if why is not None:
                self._refuse("region", "CollDetRegionCfg: %s; refused", why)
            self._reply_coll_det = True
        else:
            self._apply_config(values)

    def _refuse(self, what: str, fmt: str, *args) -> None:
        """A configuration value the sensor does not accept: nothing changes, and it says so.

        The ARS 408's RadarState has no "configuration refused" bit; of its error flags (Voltage, Temporary,
        Temperature, Interference, Persistent) the one for a condition that clears by itself is
        ``RadarState_Temporary_Error``: it is set in every RadarState of the next second, and a RadarState
        goes out with the next cycle. The reply shows what is in force — RadarState echoes the MaxDistance
        (and every other field) still in force, FilterState the filters, CollDetRegionState the regions — so an
        ECU tells a refusal from a missed deadline (which sets the same flag) by the echo. Counted in
        ``config_rejected`` and warned about once per kind.
        """
        self.counters["config_rejected"] += 1
        self._fault_until_s = max(self._fault_until_s, self._rx_t + self.period_s + STATUS_PERIOD_S)
        self._status_now = True
        self._warn_once(f"refused-{what}", fmt + " (counted in config_rejected, RadarState_Temporary_Error set "
                        "for 1 s; warned once)", *args)

    def _apply_config(self, v: dict[str, float]) -> None:
        """RadarConfiguration 0x200: each field with its valid bit; a value the sensor refuses leaves the field
        as it was (:meth:`_refuse`).

        MaxDistance is honoured from 10 m up to what the preset can see (``max_range_m``, 250 m for
        ``ars408_like``: the model cannot report farther); a larger value — the DBC allows 2046 m, the real
        sensor's extended range 1200 m — is refused, not silently capped: RadarState keeps echoing the
        MaxDistance in force and sets Temporary_Error for a second.
        """
        cfg = self.config
        self.counters["rx_config"] += 1

        def take(valid: str, name: str, allowed: range | None = None) -> int | None:
            if not int(v[valid]):
                return None
            value = int(round(v[name]))
            if allowed is not None and value not in allowed:
                self._refuse(f"cfg{name}", "RadarConfiguration: %s=%d is not allowed (allowed %d..%d); field "
                             "ignored", name, value, allowed.start, allowed.stop - 1)
                return None
            return value

        if (x := take("RadarCfg_MaxDistance_valid", "RadarCfg_MaxDistance")) is not None:
            # the loader's rule for radar.max_distance_m (presets.max_distance; the frame's 2-m grid is the DBC's)
            if presets.max_distance(self.preset, x)[1] is not None:
                self._refuse("cfgmaxd", "RadarConfiguration: MaxDistance=%d m is not allowed (allowed %d..%g m: "
                             "what preset %s can see); MaxDistance stays %g m", x, MIN_MAX_DISTANCE_M,
                             self.preset.max_range_m, self.preset.name, cfg.max_distance_m)
            else:
                cfg.max_distance_m = float(x)
        if (x := take("RadarCfg_SensorID_valid", "RadarCfg_SensorID", range(8))) is not None:
            if x != cfg.sensor_id and x in self.taken_sensor_ids():
                # two radars of one group on one sensor ID would send every message on the same CAN IDs (an
                # independent tester's finding: a 0x200 with SensorID 0 to sensor 1 of a group, or random bytes)
                self._refuse("cfgsid", "RadarConfiguration: SensorID=%d is not allowed: another radar of this "
                             "scenario holds it (allowed: an ID none of the others holds); SensorID stays %d", x,
                             cfg.sensor_id)
            elif x != cfg.sensor_id:
                # obeyed, as the ARS 408 does, and said: every frame now goes out on other CAN IDs, and a consumer
                # of the old ID sees only other_sensor_frames (an independent tester found the change silent)
                logger.warning("RadarConfiguration: SensorID %d -> %d: the node now sends on sensor %d's CAN IDs "
                               "(counted in sensor_id_changes)", cfg.sensor_id, x, x)
                self.counters["sensor_id_changes"] += 1
                cfg.sensor_id = x
        if (x := take("RadarCfg_RadarPower_valid", "RadarCfg_RadarPower", range(4))) is not None:
            cfg.radar_power = x
        if (x := take("RadarCfg_OutputType_valid", "RadarCfg_OutputType", range(3))) is not None:
            cfg.output_type = x
        if (x := take("RadarCfg_SendQuality_valid", "RadarCfg_SendQuality")) is not None:
            cfg.send_quality = bool(x)
        if (x := take("RadarCfg_SendExtInfo_valid", "RadarCfg_SendExtInfo")) is not None:
            cfg.send_ext_info = bool(x)
        if (x := take("RadarCfg_SortIndex_valid", "RadarCfg_SortIndex", range(3))) is not None:
            cfg.sort_index = x
        if (x := take("RadarCfg_StoreInNVM_valid", "RadarCfg_StoreInNVM")) is not None and x:
            # storing switched on: the configuration is written (NVMwriteStatus is the last write's status;
            # switching it off writes nothing and leaves that status). No NVM outlives the process: a restarted
            # node starts from its scenario, as a sensor whose NVM was never written
            cfg.nvm_write_ok = True
        if (x := take("RadarCfg_CtrlRelay_valid", "RadarCfg_CtrlRelay")) is not None:
            cfg.ctrl_relay = bool(x)
        if (x := take("RadarCfg_RCS_Threshold_Valid", "RadarCfg_RCS_Threshold", range(2))) is not None:
            cfg.rcs_threshold = x
        self._status_now = True   # echo the result at the next cycle

    def motion_rx_state(self, t_s: float) -> int:
        """ARS 408 MotionRxState: 0 ok, 1 speed missing, 2 yaw rate missing, 3 both missing."""
        speed_missing = self._speed is None or t_s - self._speed[1] > MOTION_TIMEOUT_S
        yaw_missing = self._yaw is None or t_s - self._yaw[1] > MOTION_TIMEOUT_S
        return int(speed_missing) | (int(yaw_missing) << 1)

    def _motion_estimate(self, t_s: float) -> tuple[tuple[float, float], float]:
        """The sensor's velocity over ground (sensor axes) and the yaw rate (rad/s) from the ego-motion input.

        Like the real sensor, missing input counts as standstill (speed and yaw rate zero), so DynProp
        goes wrong in a moving car until speed and yaw rate arrive.
        """
        state = self.motion_rx_state(t_s)
        v = self._speed[0] if not state & 1 else 0.0
        w = math.radians(self._yaw[0]) if not state & 2 else 0.0
        mx, my, myaw = self.scene.mount
        vx, vy = v - w * my, w * mx
        c, s = math.cos(-myaw), math.sin(-myaw)
        return (c * vx - s * vy, s * vx + c * vy), w

    def _boundary_frames(self, frame: RadarFrame, t_s: float, sensor_velocity: tuple[float, float], yaw_rate: float,
                         rows: bool) -> list[tuple[int, np.ndarray]]:
        """Update the road-boundary estimate and encode RoadBoundary_Left/Right (E2E protected).

        Returns (CAN ID, payload) pairs: 0x680/0x681 + 8 × SensorID (``radarnode.wire.ids``). With a
        :class:`~radarnode.wire.pipeline.BoundaryPipeline` (:meth:`defer_boundaries`) the estimate is handed to its
        process and the payloads returned are blanks of the frames' length, filled when it answers; ``rows``: the
        clusters go to it as the object level's block rows (:meth:`ObjectModel.cluster_rows
        <radarnode.radar.object_model.ObjectModel.cluster_rows>`), not from ``frame``."""
        dt = 0.0 if self._last_t is None else t_s - self._last_t
        scalars = (dt, sensor_velocity, yaw_rate, self.config.sensor_id)
        if rows:
            self._pipe.submit_rows(self._pipe_index, *self.model.cluster_rows(), scalars)
        else:
            cl = frame.clusters
            columns = (cl.dist_long_m, cl.dist_lat_m, cl.vrel_long_mps, cl.vrel_lat_mps, cl.range_m)
            if self._pipe is None:
                return self.boundary_payloads(columns, *scalars[:3])
            self._pipe.submit(self._pipe_index, columns, scalars)
        self.last_boundaries = None
        blank = self._blank
        if blank[0] != self.config.sensor_id:        # the frames' IDs, for the sensor ID in force
            blank[0] = self.config.sensor_id
            blank[1] = [(ids.own_id(base, blank[0]), blank[2][base])
                        for base in (ids.ROAD_BOUNDARY_LEFT, ids.ROAD_BOUNDARY_RIGHT)]
        return list(blank[1])

    def boundary_payloads(self, columns: tuple[np.ndarray, ...], dt_s: float, sensor_velocity: tuple[float, float],
                          yaw_rate_rps: float, sensor_id: int | None = None) -> list[tuple[int, np.ndarray]]:
        """One cycle of the road-boundary estimator on the clusters' ``columns`` (dist_long, dist_lat, vrel_long,
        vrel_lat, range) and its two frames (CAN ID, E2E-protected payload), left then right, for ``sensor_id``
        (default: the configured one; a pipeline's process is told the one in force at the cycle); sets
        ``last_boundaries``."""
        sensor = self.config.sensor_id if sensor_id is None else sensor_id
        out = []
        for side, b in enumerate(self._boundary_update(columns, dt_s, sensor_velocity, yaw_rate_rps)):
            codec, order, can_id, key = self._boundary_layout(side, sensor)
            values = self._boundary_values(b)
            protected = self._e2e.protect(key, codec.encode_values([values[k] for k in order]))
            out.append((can_id, np.frombuffer(protected, dtype=np.uint8)))
        return out

    def boundary_payloads_many(self, cycles: list[tuple]) -> list[bytes]:
        """:meth:`boundary_payloads` of several cycles in order (each ``(columns, dt_s, sensor_velocity,
        yaw_rate_rps, sensor_id)``): per cycle its two payloads joined, left then right — the same bytes, the same
        saturation counts and E2E counters, each side's frames encoded in one pass (the road-boundary process
        answers a batch of cycles at a time: :mod:`radarnode.wire.pipeline`)."""
        if not cycles:
            return []
        values: tuple[list, list] = ([], [])
        sensors = [self.config.sensor_id if c[4] is None else c[4] for c in cycles]
        for found in self._boundary_update_many(cycles):
            for side, b in enumerate(found):
                values[side].append(self._boundary_values(b))
        encoded = []
        for side in (0, 1):
            codec, order = self._boundary_layout(side, sensors[0])[:2]
            table = list(zip(*values[side]))           # a column per signal, in _BOUNDARY_SIGNALS' order
            encoded.append(codec.encode({name: np.array(table[k], dtype=np.float64)
                                         for name, k in zip(codec.signal_names, order)}))
        protect = self._e2e.protect
        return [protect(self._boundary_layout(0, sensor)[3], left.tobytes())
                + protect(self._boundary_layout(1, sensor)[3], right.tobytes())
                for sensor, left, right in zip(sensors, encoded[0], encoded[1])]

    def _boundary_update(self, columns: tuple[np.ndarray, ...], dt_s: float, sensor_velocity: tuple[float, float],
                         yaw_rate_rps: float) -> tuple[Boundary, Boundary]:
        """One cycle of the road-boundary estimator on the clusters' columns; sets ``last_boundaries``."""
        x_m, y_m, vx, vy, r = columns
        r = np.maximum(r, 1e-6)
        rate = (x_m * vx + y_m * vy) / r
        self.last_boundaries = self.boundaries.update(x_m, y_m, rate, dt_s, sensor_velocity, yaw_rate_rps, r)
        return self.last_boundaries

    def _boundary_update_many(self, cycles: list[tuple]) -> list[tuple[Boundary, Boundary]]:
        """:meth:`_boundary_update` of several cycles (:meth:`boundary_payloads_many`'s), the clusters' columns of
        all of them in one pass (:meth:`RoadBoundaryEstimator.update_many
        <radarnode.perception.boundaries.RoadBoundaryEstimator.update_many>`): the same estimates. A cycle's range
        column may be None: the clusters' ``np.hypot(dist_long, dist_lat)``, as ClusterList.range_m computes it."""
        x, y, vx, vy = (np.concatenate([c[0][k] for c in cycles]) for k in range(4))
        if all(c[0][4] is None for c in cycles):
            r = np.hypot(x, y)
        else:
            r = np.concatenate([np.hypot(c[0][0], c[0][1]) if c[0][4] is None else c[0][4] for c in cycles])
        np.maximum(r, 1e-6, out=r)
        rate = (x * vx + y * vy) / r
        found = self.boundaries.update_many(x, y, rate, r, [c[0][0].size for c in cycles],
                                            [c[1:4] for c in cycles])
        self.last_boundaries = found[-1]
        return found

    @staticmethod
    def _boundary_values(b: Boundary) -> tuple:
        """A boundary's signals in :data:`_BOUNDARY_SIGNALS`' order (CRC and counter 0: the E2E protection's)."""
        return (0, 0, int(b.valid), round(7 * b.confidence), b.offset_m, math.degrees(b.heading_rad),
                b.curvature_1pm, 4 * math.floor(b.range_start_m / 4), b.range_end_m)

    #: RoadBoundary_Left/Right's signals, as :meth:`boundary_payloads` computes them (after the side's prefix)
    _BOUNDARY_SIGNALS = ("CRC", "Counter", "Valid", "Confidence", "LatOffset", "Heading", "Curvature", "RangeStart",
                         "RangeEnd")

    def _boundary_layout(self, side: int, sensor: int) -> tuple:
        """Side ``side``'s (0 left, 1 right) boundary frame for ``sensor``: its codec, where each of its signals is
        among :data:`_BOUNDARY_SIGNALS`, its CAN ID and its E2E key (made once a side and sensor ID)."""
        layouts = self.__dict__.setdefault("_boundary_layouts", {})
        layout = layouts.get((side, sensor))
        if layout is None:
            base, prefix = ((ids.ROAD_BOUNDARY_LEFT, "RBL"), (ids.ROAD_BOUNDARY_RIGHT, "RBR"))[side]
            codec = self.own_codecs[base]
            names = [f"{prefix}_{name}" for name in self._BOUNDARY_SIGNALS]
            if sorted(names) != sorted(codec.signal_names):
                raise WireError(f"message {codec.name}: signals {', '.join(codec.signal_names)}; expected "
                                f"{', '.join(names)}")
            layout = layouts[(side, sensor)] = (codec, [names.index(n) for n in codec.signal_names],
                                                ids.own_id(base, sensor), ids.e2e_key(base, sensor))
        return layout

    @property
    def boundary_pipe(self):
        """The BoundaryPipeline this node hands its boundaries to (:meth:`defer_boundaries`), or None."""
        return self._pipe

    def boundary_state(self) -> tuple:
        """What the road-boundary estimate carries from cycle to cycle: the estimator, the E2E counters of its
        frames, its last estimate (a pipeline's process gives it back with :meth:`resume_boundaries`)."""
        return self.boundaries, self._e2e, self.last_boundaries

    def resume_boundaries(self, state: tuple) -> None:
        """Compute the boundaries here again, from ``state`` (:meth:`boundary_state` of the process that had them)."""
        self.boundaries, self._e2e, self.last_boundaries = state
        self.defer_boundaries(None, 0)

    def defer_boundaries(self, pipe, index: int) -> None:
        """Hand every cycle's road-boundary estimate to ``pipe`` (a :class:`~radarnode.wire.pipeline.BoundaryPipeline`,
        this node its ``index``-th) instead of computing it here: :meth:`cycle` then returns the two frames blank,
        and the pipe fills them in when its process has computed them (the output's ``boundaries`` stay None: a
        reader of the estimate decodes the frames; at the object level, while objects are sent, the frame's cluster
        list stays empty too: its rows go to the pipe)."""
        self._pipe, self._pipe_index = pipe, index
        # the frames' blank payloads, and their (CAN ID, payload) pairs for the sensor ID they were made for
        self._blank = [None, None, {base: np.zeros(self.own_codecs[base].length, dtype=np.uint8)
                                    for base in (ids.ROAD_BOUNDARY_LEFT, ids.ROAD_BOUNDARY_RIGHT)}]
        # the object level hands its clusters over as its blocks' rows (the list itself is read by nobody here
        # while the objects are sent); a pipe that lost its process (no submit_rows) refuses every cycle as it is
        self._pipe_rows = (pipe is not None and hasattr(pipe, "submit_rows")
                           and callable(getattr(self.model, "cluster_rows", None)))

    # --- output -------------------------------------------------------------
    @staticmethod
    def _wire_id(base_id: int, sensor_id: int) -> int:
        """The CAN ID on the wire of a frame a cycle lists under ``base_id``: ARS 408 messages are shifted by
        0x10 × SensorID; own messages are listed with their final ID."""
        return base_id if ids.split_own_id(base_id) is not None else P.shifted(base_id, sensor_id)

    def _status_frames(self, t_s: float) -> list[tuple[int, np.ndarray]]:
        cfg = self.config
        state = self.codecs[P.RADAR_STATE].encode({
            "RadarState_NVMwriteStatus": int(cfg.nvm_write_ok), "RadarState_NVMReadStatus": 1,
            "RadarState_MaxDistanceCfg": cfg.max_distance_m, "RadarState_Voltage_Error": 0,
            "RadarState_Temporary_Error": int(t_s < self._fault_until_s),
            "RadarState_Temperature_Error": 0, "RadarState_Interference": 0,
            "RadarState_Persistent_Error": 0, "RadarState_RadarPowerCfg": cfg.radar_power,
            "RadarState_SensorID": cfg.sensor_id, "RadarState_SortIndex": cfg.sort_index,
            "RadarState_CtrlRelayCfg": int(cfg.ctrl_relay), "RadarState_OutputTypeCfg": cfg.output_type,
            "RadarState_SendQualityCfg": int(cfg.send_quality), "RadarState_SendExtInfoCfg": int(cfg.send_ext_info),
            "RadarState_MotionRxState": self.motion_rx_state(t_s), "RadarState_RCS_Threshold": cfg.rcs_threshold,
        })[0]
        major, minor, patch = P.FIRMWARE_VERSION
        version = self.codecs[P.VERSION_ID].encode({
            "Version_MajorRelease": major, "Version_MinorRelease": minor, "Version_PatchLevel": patch,
            "Version_ExtendedRange": 0, "Version_CountryCode": 0})[0]
        return [(P.RADAR_STATE, state), (P.VERSION_ID, version)]

    def _lifetimes(self, ol, t_s: float) -> np.ndarray:
        """Seconds since the model's tracker first reported each object (for the Lifetime filter), shape (n,).

        An object is born when its ID was not in the previous cycle's list or its MeasState is "new"."""
        if not len(ol):
            if self._born_any:
                self._born.fill(np.nan)
                self._born_any = False
            return np.zeros(0)
        self._born_any = True
        slot = np.clip(ol.id, 0, MAX_OBJECT_ID)
        born = self._born[slot]
        new = np.isnan(born) | (ol.meas_state == MEAS_NEW)
        born = np.where(new, t_s, born)
        self._born[:] = np.nan
        self._born[slot] = born
        return t_s - born

    def _as_sent(self, lst, general: int, extended: int | None = None):
        """The list with the fields the filters test as a receiver decodes them (on their wire grids, clipped to
        their ranges), so that a filter's [Min, Max] holds for the values sent; the list itself when no filter
        is active."""
        if not self.filters.active(TYPE_OBJECT if extended is not None else TYPE_CLUSTER):
            return lst
        g = self.codecs[general]
        prefix = g.signal_names[0].split("_")[0]           # Obj / Cluster
        sent = {"dist_long_m": "DistLong", "dist_lat_m": "DistLat", "vrel_long_mps": "VrelLong",
                "vrel_lat_mps": "VrelLat", "rcs_dbsm": "RCS"}
        values = {attr: g.as_sent(f"{prefix}_{sig}", getattr(lst, attr)) for attr, sig in sent.items()}
        if extended is not None:
            e = self.codecs[extended]
            values.update(length_m=e.as_sent("Obj_Length", lst.length_m), width_m=e.as_sent("Obj_Width", lst.width_m))
        return dataclasses.replace(lst, **values)

    def _priority(self, ranges: np.ndarray, rcs: np.ndarray) -> np.ndarray:
        """Indices from most to least important: by RCS when SortIndex says so, else nearest first."""
        return np.argsort(-rcs, kind="stable") if self.config.sort_index == 2 else np.argsort(ranges, kind="stable")

    def _send_order(self, ids: np.ndarray, ranges: np.ndarray, rcs: np.ndarray) -> np.ndarray:
        if self.config.sort_index == 0:
            return np.argsort(ids, kind="stable")
        return self._priority(ranges, rcs)

    def _fit(self, n: int, frames_per_item: list[int], fixed_bits: int) -> int:
        """How many list items fit in the cycle's bus-load budget."""
        budget = self.bus_load_limit * self.bitrate * self.period_s - fixed_bits
        per_item = sum(frame_bits(int(d)) for d in frames_per_item)
        return max(0, min(n, int(budget // per_item))) if per_item else n

    def _runtime_config(self) -> RuntimeConfig:
        """What the configuration asks of the model, the same object while it stays the same (a new one, checked,
        when it changes: the model compares it by identity first)."""
        cfg = self.config
        key = (min(cfg.max_distance_m, self.preset.max_range_m), 3.0 * cfg.radar_power, cfg.rcs_threshold == 1,
               cfg.output_type == P.OUTPUT_CLUSTERS or self.boundaries is not None)
        last = self._runtime
        if last is None or last[0] != key:
            last = self._runtime = (key, RuntimeConfig(max_distance_m=key[0], power_reduction_db=key[1],
                                                       high_sensitivity=key[2], clusters=key[3]))
        return last[1]

    def cycle(self, t_s: float, timestamp: float | None = None) -> CycleOutput:
        """Run the model at ``t_s`` and return this cycle's frames in bus order.

        ``timestamp`` is the time of the first frame (default ``t_s``); later
        frames are spaced by their nominal time on the wire.
        """
        cfg = self.config
        runtime = self._runtime_config()
        sensor_velocity, yaw_rate = self._motion_estimate(t_s)
        # with a boundary process and an object list to send, the cluster list is computed for that process only:
        # the object level hands it over as rows (no list object, no DynProp here)
        rows = self._pipe_rows and self._pipe is not None and self.boundaries is not None and runtime.clusters \
            and cfg.output_type == P.OUTPUT_OBJECTS
        if rows:
            frame, view = self.model.step(t_s, runtime, sensor_velocity + (yaw_rate,), cluster_list=False)
        else:
            frame, view = self.model.step(t_s, runtime, sensor_velocity + (yaw_rate,))
        own = self._boundary_frames(frame, t_s, sensor_velocity, yaw_rate, rows) if self.boundaries is not None \
            else []
        self._last_t = t_s
        out: list[tuple[int, np.ndarray]] = []
        if self._status_now or t_s + 1e-9 >= self._next_status_s:
            out += self._status_frames(t_s)
            self._status_now = False
            while self._next_status_s <= t_s + 1e-9:
                self._next_status_s += STATUS_PERIOD_S
        if self._reply_filters:
            out += [(base, np.frombuffer(data, np.uint8)) for base, data in self.filters.state_payloads()]
            self._reply_filters = False
        # CollDetState and the regions' states go out right before the list header: every cycle while collision
        # detection is on (a consumer learns from it that Obj_4_Warning follows), once after a change otherwise
        coll_det_now = self.coll_det.active or self._reply_coll_det
        self._reply_coll_det = False
        warnings = self.coll_det.active and cfg.output_type == P.OUTPUT_OBJECTS
        relay = self.coll_det.active and cfg.ctrl_relay
        fixed = [len(p) for _, p in out + own] + [8] + (self.coll_det.state_dlcs() if coll_det_now else []) \
            + ([1] if relay else [])
        fixed_bits = sum([STANDARD_BITS_WORST[d] for d in fixed])
        budget = self.bus_load_limit * self.bitrate * self.period_s
        if fixed_bits > budget:
            # the frames every such cycle sends (states, the list's header, the boundaries) alone exceed the budget:
            # no list item can make it fit (an independent tester saw it at 10 kbit/s with only the drops warned of)
            self.counters["cycles_over_budget"] += 1
            self._warn_once("overbudget", "cycle at t=%.3f s: its fixed frames alone need %d bits, more than %.0f %% "
                            "of %d bit/s in %.1f ms (%d bits); the bus-load budget cannot be kept at this bit rate "
                            "(counted in cycles_over_budget; warned once)", t_s, fixed_bits,
                            100 * self.bus_load_limit, self.bitrate, 1e3 * self.period_s, int(budget))
        lifetime = self._lifetimes(frame.objects, t_s)
        dropped = filtered = 0
        header_at = len(out)
        evaluated = False
        if cfg.output_type == P.OUTPUT_OBJECTS:
            ol = frame.objects
            if len(ol):                  # (an empty list: nothing to filter, fit or order)
                mask = self.filters.object_mask(self._as_sent(ol, P.OBJ_GENERAL, P.OBJ_EXTENDED), lifetime)
                filtered = int((~mask).sum())
                keep = self._priority(ol.range_m, ol.rcs_dbsm)
                keep = keep[mask[keep]][:MAX_OBJECTS]
                cap = self.filters.max_count(TYPE_OBJECT)
                if cap is not None and len(keep) > cap:
                    filtered += len(keep) - cap
                    keep = keep[:cap]
                groups = [8] + ([7] if cfg.send_quality else []) + ([8] if cfg.send_ext_info else []) \
                    + ([4] if warnings else [])
                n_fit = self._fit(len(keep), groups, fixed_bits)
                dropped = len(keep) - n_fit
                ol = ol.take(keep[:n_fit])
                ol = ol.take(self._send_order(ol.id, ol.range_m, ol.rcs_dbsm))
                frame.objects = ol
            status = self.codecs[P.OBJ_STATUS]
            values = {"Obj_NofObjects": len(ol), "Obj_MeasCounter": self._meas_counter,
                      "Obj_InterfaceVersion": P.INTERFACE_VERSION}
            out.append((P.OBJ_STATUS, status.encode_values([values[name] for name in status.signal_names])))
            if len(ol):
                general, quality, extended = P.object_signals(ol)
                rows = self.codecs[P.OBJ_GENERAL].encode(general)
                out += [(P.OBJ_GENERAL, row) for row in rows]
                if cfg.send_quality:
                    out += [(P.OBJ_QUALITY, row) for row in self.codecs[P.OBJ_QUALITY].encode(quality)]
                if cfg.send_ext_info:
                    out += [(P.OBJ_EXTENDED, row) for row in self.codecs[P.OBJ_EXTENDED].encode(extended)]
            if warnings:
                # the regions are tested on the positions as sent (decoded back from the frames)
                sent = self.codecs[P.OBJ_GENERAL].decode(rows) if len(ol) else \
                    {"Obj_DistLong": np.zeros(0), "Obj_DistLat": np.zeros(0)}
                result = self.coll_det.evaluate(t_s, ol.id, sent["Obj_DistLong"], sent["Obj_DistLat"])
                evaluated = True
                if len(ol):
                    out += [(P.OBJ_WARNING, row) for row in self.codecs[P.OBJ_WARNING].encode(
                        {"Obj_ID": ol.id, "Obj_CollDetRegionBitfield": result.bits})]
        elif cfg.output_type == P.OUTPUT_CLUSTERS:
            cl = frame.clusters
            mask = self.filters.cluster_mask(self._as_sent(cl, P.CLUSTER_GENERAL))
            cap = self.filters.max_count(TYPE_CLUSTER)
            if cap is not None and int(mask.sum()) > cap:      # keep the nearest, in near-before-far order
                idx = np.flatnonzero(mask)
                mask[:] = False
                mask[np.sort(idx[np.argsort(cl.range_m[idx], kind="stable")[:cap]])] = True
            filtered = int((~mask).sum())
            if filtered:
                cl = cl.take(mask)
                cl.id = np.arange(len(cl), dtype=np.int64)
            groups = [8] + ([5] if cfg.send_quality else [])
            n_fit = self._fit(len(cl), groups, fixed_bits)
            dropped = len(cl) - n_fit
            if dropped:  # drop the farthest, keeping near-before-far order
                cl = cl.take(np.sort(np.argsort(cl.range_m, kind="stable")[:n_fit]))
                cl.id = np.arange(len(cl), dtype=np.int64)
            frame.clusters = cl
            general, quality = P.cluster_signals(cl)
            n_near = int(cl.is_near.sum())
            out.append((P.CLUSTER_STATUS, self.codecs[P.CLUSTER_STATUS].encode({
                "Cluster_NofClustersNear": n_near, "Cluster_NofClustersFar": len(cl) - n_near,
                "Cluster_MeasCounter": self._meas_counter, "Cluster_InterfaceVersion": P.INTERFACE_VERSION})[0]))
            if len(cl):
                out += [(P.CLUSTER_GENERAL, row) for row in self.codecs[P.CLUSTER_GENERAL].encode(general)]
                if cfg.send_quality:
                    out += [(P.CLUSTER_QUALITY, row) for row in self.codecs[P.CLUSTER_QUALITY].encode(quality)]
        if coll_det_now:
            if not evaluated:            # no object list this cycle: the regions see no objects
                self.coll_det.evaluate(t_s, np.zeros(0, np.int64), np.zeros(0), np.zeros(0))
            state = [(base, np.frombuffer(data, np.uint8))
                     for base, data in self.coll_det.state_payloads(self._meas_counter)]
            out[header_at:header_at] = state
            header_at += len(state)
        if relay:
            out.append((P.COLL_DET_RELAY, self.codecs[P.COLL_DET_RELAY].encode(
                {"CollDetRelayCtrl_Param": self.coll_det.relay_bits()})[0]))
        if filtered:
            self.counters["items_filtered"] += filtered
        if dropped:
            self.counters["objects_dropped_busload"] += dropped
            self._warn_once("busload", "cycle at t=%.3f s does not fit %.0f %% of %d bit/s in %.1f ms: dropped %d "
                            "lowest-priority entries (counted in objects_dropped_busload; warned once)",
                            t_s, 100 * self.bus_load_limit, self.bitrate, 1e3 * self.period_s, dropped)
        self._meas_counter = (self._meas_counter + 1) & 0xFFFF
        out += own
        dlcs = [len(p) for _, p in out]
        t0 = t_s if timestamp is None else timestamp
        messages, elapsed = [], 0                  # frame k at t0 + the nominal bits of the frames before it
        sensor, bitrate = cfg.sensor_id, self.bitrate
        wire = self._wire_id_tables.setdefault(sensor, {})     # (filled as the IDs come)
        for (base, payload), dlc in zip(out, dlcs):
            can_id = wire.get(base)
            if can_id is None:
                can_id = wire[base] = self._wire_id(base, sensor)
            messages.append(can.Message(arbitration_id=can_id, is_extended_id=False,
                                        data=payload if type(payload) is bytes else payload.tobytes(),
                                        timestamp=t0 + elapsed / bitrate, check=False))
            elapsed += STANDARD_BITS_NOMINAL[dlc]
        self.counters["cycles"] += 1
        self.counters["frames"] += len(messages)
        result = CycleOutput(t_s, messages, frame, view, sum([STANDARD_BITS_WORST[d] for d in dlcs]), dropped,
                             boundaries=(self.last_boundaries if own else None), lead=min(header_at + 1, len(messages)))
        if own and self._pipe is not None:
            self._pipe.attach(messages[-len(own):])
        return result

    def withdraw(self, out: CycleOutput) -> None:
        """Un-count a cycle :meth:`cycle` computed that is not sent (late, or the run stopped before its
        deadline): ``counters["cycles"]`` and ``["frames"]`` count what went out (its MeasCounter stays used)."""
        self.counters["cycles"] -= 1
        self.counters["frames"] -= len(out.messages)

    def sent_late(self, t_s: float, late_s: float) -> None:
        """Flag cycle ``t_s``, which the bus took ``late_s`` after its deadline (beyond the tolerance: the process
        was preempted between the runner's check and the send): counted in ``cycles_sent_late`` and reported as
        :meth:`missed_deadline` reports a dropped cycle, Temporary_Error in RadarState for the next second."""
        self.counters["cycles_sent_late"] += 1
        self._fault_until_s = max(self._fault_until_s, t_s + self.period_s + STATUS_PERIOD_S)
        self._status_now = True
        # (the cause named by what is known: a bus that did not take frames (tx_failed) waited its send timeout each,
        # and that was blamed on preemption: a tester's finding)
        cause = "the bus did not take frames in time: tx_failed" if self.counters.get("tx_failed") else \
            "the process was preempted while sending"
        self._warn_once("sent_late", "cycle at t=%.3f s went out %.1f ms after its deadline (%s); flagged in "
                        "RadarState_Temporary_Error and counted in cycles_sent_late (warned once)", t_s,
                        1e3 * late_s, cause)

    def missed_deadline(self, t_s: float, late_s: float, skipped: int = 0, computed: bool = True) -> None:
        """Flag cycles not sent because they could not be ready on their deadline.

        ``computed``: cycle ``t_s`` was computed and was ``late_s`` late (its MeasCounter is used); otherwise
        ``skipped`` cycles from ``t_s`` on were not computed at all (MeasCounter moves on by as many), so a
        consumer counts every one of them as lost. The ARS 408 reports faults in RadarState, and of its error
        bits (Voltage, Temperature, Interference, Persistent, Temporary) a cycle lost to load is a temporary
        one: Temporary_Error ("Temporary error active" in the DBC) is set in every RadarState of the next
        second, and one goes out with the next cycle sent. ``cycles_missed_deadline`` counts them all.
        """
        lost = (1 if computed else 0) + skipped
        if not computed:
            self._meas_counter = (self._meas_counter + skipped) & 0xFFFF
        self.counters["cycles_missed_deadline"] += lost
        self._fault_until_s = t_s + lost * self.period_s + STATUS_PERIOD_S
        self._status_now = True
        self._warn_once("deadline", "cycle at t=%.3f s %s: not sent (%d cycle(s)); flagged in "
                        "RadarState_Temporary_Error and counted in cycles_missed_deadline (warned once)", t_s,
                        f"went out of its tolerance, {1e3 * late_s:.1f} ms after its deadline" if computed else
                        f"could not be computed before its deadline (by {1e3 * late_s:.1f} ms)", lost)

    def warn_once(self, key: str, fmt: str, *args) -> None:
        """Log a warning the first time ``key`` comes up (per-frame trouble is counted, not logged each time)."""
        self._warn_once(key, fmt, *args)

    def _warn_once(self, key: str, fmt: str, *args) -> None:
        if key not in self._warned:
            self._warned.add(key)
            logger.warning(fmt, *args)


class EgoMotionSender:
    """The vehicle side: SpeedInformation 0x300 and YawRateInformation 0x301 from the scenario's ego.

    In a car another ECU sends these; ``radarnode run`` and ``radarnode log``
    include one so that the node's MotionRxState is "ok" and logs are complete.
    Given the node's ``config``, it follows the node's sensor ID when a
    RadarConfiguration moves it (``node --send-ego-motion``: before, the
    frames stayed at the old ID, where the node no longer listened).
    """

    def __init__(self, scene: Scene, sensor_id: int = 0, database=None, config=None) -> None:
        db = database if database is not None else load_database()
        self.scene = scene
        self._sensor_id = sensor_id
        self._config = config
        self._speed = MessageCodec(db.get_message_by_frame_id(P.SPEED_INFO))
        self._yaw = MessageCodec(db.get_message_by_frame_id(P.YAW_RATE_INFO))
        self._last: tuple = (None, b"", b"")     # the last (speed, direction, yaw rate) and its two payloads

    @property
    def sensor_id(self) -> int:
        return self._config.sensor_id if self._config is not None else self._sensor_id

    def frames(self, t_s: float, timestamp: float | None = None) -> list[can.Message]:
        ego = self.scene.ego_state(t_s)
        speed = abs(ego.speed_mps)
        direction = 0 if speed < 0.01 else (1 if ego.speed_mps > 0 else 2)
        ts = t_s if timestamp is None else timestamp
        yaw = math.degrees(ego.yaw_rate_rps)
        if (speed, direction, yaw) != self._last[0]:        # encoded again only when the values change
            sp = self._speed.encode({"RadarDevice_Speed": speed, "RadarDevice_SpeedDirection": direction})[0]
            yr = self._yaw.encode({"RadarDevice_YawRate": yaw})[0]
            self._last = ((speed, direction, yaw), sp.tobytes(), yr.tobytes())
        _, sp, yr = self._last
        return [can.Message(arbitration_id=P.shifted(P.SPEED_INFO, self.sensor_id), data=sp,
                            is_extended_id=False, timestamp=ts, check=False),
                can.Message(arbitration_id=P.shifted(P.YAW_RATE_INFO, self.sensor_id), data=yr,
                            is_extended_id=False, timestamp=ts, check=False)]
