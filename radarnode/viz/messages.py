"""One Foxglove message from one record: decoded lists, boundaries and frames, the ECU's status, the truth.

Foxglove's well-known schemas (``foxglove.messages``, protobuf) for what its 3-D and Image panels draw; JSON
with a JSON Schema for radarnode's own records (CAN frames, the ECU's status, the ego's state), which the Raw
Messages, Plot and State Transitions panels read by field name.

Frames (all right-handed, x forward, y left, z up, metres): ``world`` (the road's start on the ground),
``ego`` (the rear-axle centre on the ground, :class:`radarnode.scene.world.EgoState`) and ``radar`` (the
sensor on its mount, ``radar.mount`` of the scenario: position, height ``z_m`` and yaw). The radar reports
positions in its own frame and nothing about height, so objects, clusters and boundaries are drawn in the
``radar`` frame standing on the ground (z = −mount height), with a height by class for the boxes.
"""

from __future__ import annotations

import math

import can
import numpy as np
from foxglove.messages import (Color, CubePrimitive, FrameTransform, FrameTransforms, ImageAnnotations,
                               KeyValuePair, LinePrimitive, LinePrimitiveLineType, PackedElementField,
                               PackedElementFieldNumericType, Point2, Point3, PointCloud, PointsAnnotation,
                               PointsAnnotationType, Pose, Quaternion, RawImage, SceneEntity, SceneEntityDeletion,
                               SceneEntityDeletionType, SceneUpdate, TextAnnotation, TextPrimitive, Timestamp,
                               Vector3)

from radarnode.perception.boundaries import Boundary
from radarnode.perception.types import CLASS_NAMES, DYN_NAMES, ClusterList, ObjectList
from radarnode.wire.busdbc import signal_value

WORLD, EGO, RADAR = "world", "ego", "radar"

#: drawn height of an object's box by ARS 408 class (the radar reports none), m; -1 (no extended frame): 1 m
CLASS_HEIGHT_M = {0: 1.0, 1: 1.5, 2: 3.5, 3: 1.8, 4: 1.4, 5: 1.7, 6: 1.2, 7: 1.0}
CLASS_RGB = {0: (0.7, 0.7, 0.7), 1: (0.2, 0.6, 1.0), 2: (1.0, 0.6, 0.1), 3: (1.0, 0.2, 0.2), 4: (0.8, 0.3, 1.0),
             5: (0.2, 0.9, 0.4), 6: (0.9, 0.9, 0.2), 7: (0.7, 0.7, 0.7)}
TRUTH_RGB = (1.0, 1.0, 1.0)
BOUNDARY_RGB = (0.0, 0.9, 0.9)
#: matplotlib's viridis at 0, 1/8, …, 1 (the colour map of ``radarnode image``), interpolated linearly
VIRIDIS = np.array([(0.267, 0.0049, 0.3294), (0.2788, 0.1755, 0.4834), (0.2297, 0.3224, 0.5457),
                    (0.1727, 0.4488, 0.5579), (0.1276, 0.5669, 0.5506), (0.1579, 0.6838, 0.5017),
                    (0.3692, 0.7889, 0.3829), (0.6785, 0.8637, 0.1895), (0.9932, 0.9062, 0.1439)])
RD_FLOOR_DB = -50.0          # the range–Doppler image spans this much below its strongest cell


def stamp(t_s: float) -> Timestamp:
    """A Foxglove timestamp of ``t_s`` seconds (scenario time or Unix time, as the frames carry it)."""
    t = max(float(t_s), 0.0)
    sec = int(math.floor(t))
    return Timestamp(sec=sec, nsec=min(int(round((t - sec) * 1e9)), 999_999_999))


def _color(rgb: tuple[float, float, float], a: float = 1.0) -> Color:
    return Color(r=rgb[0], g=rgb[1], b=rgb[2], a=a)


def _yaw(angle_rad: float) -> Quaternion:
    return Quaternion(x=0.0, y=0.0, z=math.sin(angle_rad / 2.0), w=math.cos(angle_rad / 2.0))


def _pose(x: float, y: float, z: float, yaw_rad: float = 0.0) -> Pose:
    return Pose(position=Vector3(x=x, y=y, z=z), orientation=_yaw(yaw_rad))


def _kv(d: dict) -> list[KeyValuePair]:
    return [KeyValuePair(key=k, value=v if isinstance(v, str) else _num(v)) for k, v in d.items()]


def _num(v: float) -> str:
    """A number as metadata text: exact for the wire's LSBs (0.2 m, 0.25 m/s …), '-' for not available.

    Rounded to 6 decimals first: a decoded value is offset + raw × scale with an LSB of 0.001 or coarser, so
    this keeps it exact and drops the binary noise (-204.6 + 1023 × 0.2 is 2.84e-14, shown as 0)."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    v = round(float(v), 6) + 0.0          # + 0.0: no "-0"
    if v.is_integer():
        return str(int(v))
    return f"{v:.6g}"


def _label(choices: dict | None, code: int) -> str:
    if code < 0 or not choices or code not in choices:
        return "-"
    return str(choices[code])


def box_centre(x_m: float, y_m: float, yaw_rad: float, length_m: float, width_m: float) -> tuple[float, float]:
    """The centre of a box whose point nearest to the sensor (radarnode's reference point of an object) is
    (``x_m``, ``y_m``): the rear face lies at the point; a point more than half a width to the side is the rear
    corner facing the sensor, else the sensor looks at the rear face and the point is taken as its middle."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    along, across = c * x_m + s * y_m, -s * x_m + c * y_m          # the point in the box's axes
    along += 0.5 * length_m
    if abs(across) >= 0.5 * width_m:
        across += math.copysign(0.5 * width_m, across)
    return c * along - s * across, s * along + c * across


def objects_update(ol: ObjectList, t_s: float, *, mount_z_m: float = 0.5,
                   prob_names: dict | None = None) -> SceneUpdate:
    """The decoded object list as boxes in the ``radar`` frame, replacing the previous list.

    One entity per object, ``id`` ``"object <ID>"``: a translucent box (length × width from Obj_3_Extended,
    1 m where it was not sent; a height by class) placed by :func:`box_centre` along the reported orientation;
    a label with ID, class, relative speed
    and existence probability; the decoded values as metadata (``id``, ``class``, ``dyn_prop``,
    ``dist_long_m``, ``dist_lat_m``, ``vrel_long_mps``, ``vrel_lat_mps``, ``rcs_dbsm``, ``length_m``,
    ``width_m``, ``orientation_deg``, ``prob_of_exist``, ``meas_state``).
    """
    ts = stamp(t_s)
    entities = []
    for k in range(len(ol)):
        oid, cls = int(ol.id[k]), int(ol.obj_class[k])
        x, y = float(ol.dist_long_m[k]), float(ol.dist_lat_m[k])
        length = float(ol.length_m[k]) if np.isfinite(ol.length_m[k]) and ol.length_m[k] > 0 else 1.0
        width = float(ol.width_m[k]) if np.isfinite(ol.width_m[k]) and ol.width_m[k] > 0 else 1.0
        yaw = float(ol.orientation_rad[k]) if np.isfinite(ol.orientation_rad[k]) else 0.0
        height = CLASS_HEIGHT_M.get(cls, 1.0)
        cx, cy = box_centre(x, y, yaw, length, width)
        cls_name = CLASS_NAMES[cls] if 0 <= cls < len(CLASS_NAMES) else "-"
        prob = _label(prob_names, int(ol.prob_of_exist[k]))
        rgb = CLASS_RGB.get(cls, (0.7, 0.7, 0.7))
        text = f"{oid} {cls_name}\n{float(ol.vrel_long_mps[k]):+.2f} m/s\nP {prob}"
        meta = {"id": oid, "class": cls_name, "dyn_prop": DYN_NAMES[int(ol.dyn_prop[k])] if 0 <= ol.dyn_prop[k] < 8
                else "-", "dist_long_m": x, "dist_lat_m": y, "vrel_long_mps": float(ol.vrel_long_mps[k]),
                "vrel_lat_mps": float(ol.vrel_lat_mps[k]), "rcs_dbsm": float(ol.rcs_dbsm[k]),
                "length_m": float(ol.length_m[k]), "width_m": float(ol.width_m[k]),
                "orientation_deg": math.degrees(float(ol.orientation_rad[k])), "prob_of_exist": prob,
                "meas_state": int(ol.meas_state[k])}
        entities.append(SceneEntity(
            timestamp=ts, frame_id=RADAR, id=f"object {oid}", metadata=_kv(meta),
            cubes=[CubePrimitive(pose=_pose(cx, cy, 0.5 * height - mount_z_m, yaw),
                                 size=Vector3(x=length, y=width, z=height), color=_color(rgb, 0.55))],
            texts=[TextPrimitive(pose=_pose(cx, cy, height - mount_z_m + 0.6), billboard=True, font_size=14.0,
                                 scale_invariant=True, color=_color((1.0, 1.0, 1.0)), text=text)]))
    return SceneUpdate(deletions=[SceneEntityDeletion(timestamp=ts, type=SceneEntityDeletionType.All)],
                       entities=entities)


#: the point fields of :func:`clusters_cloud`, each float32, in this order
CLUSTER_FIELDS = ("x", "y", "z", "rcs_dbsm", "vrel_long_mps", "vrel_lat_mps", "dyn_prop", "id", "ambig_state",
                  "pdh0", "is_near")


def clusters_cloud(cl: ClusterList, t_s: float, *, mount_z_m: float = 0.5) -> PointCloud:
    """The decoded cluster list as points in the ``radar`` frame (on the ground), one per cluster.

    Fields (float32, little-endian, :data:`CLUSTER_FIELDS`): position, RCS, relative speed, DynProp, ID,
    AmbigState, PdH0 and 1 for near-scan clusters; the 3-D panel colours by any of them.
    """
    n = len(cl)
    cols = [cl.dist_long_m, cl.dist_lat_m, np.full(n, -mount_z_m), cl.rcs_dbsm, cl.vrel_long_mps, cl.vrel_lat_mps,
            cl.dyn_prop, cl.id, cl.ambig_state, cl.pdh0, cl.is_near]
    data = np.column_stack([np.asarray(c, dtype=np.float64) for c in cols]).astype("<f4") if n else \
        np.zeros((0, len(cols)), dtype="<f4")
    fields = [PackedElementField(name=name, offset=4 * i, type=PackedElementFieldNumericType.Float32)
              for i, name in enumerate(CLUSTER_FIELDS)]
    return PointCloud(timestamp=stamp(t_s), frame_id=RADAR, pose=_pose(0.0, 0.0, 0.0),
                      point_stride=4 * len(CLUSTER_FIELDS), fields=fields, data=data.tobytes())


def boundary_update(side: str, b: Boundary, t_s: float, *, mount_z_m: float = 0.5, step_m: float = 2.0
                    ) -> SceneUpdate:
    """One decoded road boundary (``side`` 'left' or 'right') as a line over its valid range, on the ground,
    replacing that side's previous line; an unavailable boundary deletes it."""
    ts = stamp(t_s)
    ident = f"boundary {side}"
    if not b.valid or b.range_end_m <= b.range_start_m:
        return SceneUpdate(deletions=[SceneEntityDeletion(timestamp=ts, type=SceneEntityDeletionType.MatchingId,
                                                          id=ident)])
    xs = np.arange(b.range_start_m, b.range_end_m + 1e-9, step_m)
    if xs[-1] < b.range_end_m:
        xs = np.append(xs, b.range_end_m)
    ys = b.y_at(xs)
    meta = {"side": side, "offset_m": b.offset_m, "heading_deg": math.degrees(b.heading_rad),
            "curvature_1pm": b.curvature_1pm, "range_start_m": b.range_start_m, "range_end_m": b.range_end_m,
            "confidence": b.confidence}
    line = LinePrimitive(type=LinePrimitiveLineType.LineStrip, pose=_pose(0.0, 0.0, 0.0), thickness=0.3,
                         points=[Point3(x=float(x), y=float(y), z=-mount_z_m + 0.3) for x, y in zip(xs, ys)],
                         color=_color(BOUNDARY_RGB))
    return SceneUpdate(entities=[SceneEntity(timestamp=ts, frame_id=RADAR, id=ident, metadata=_kv(meta),
                                             lines=[line])])


_BOX_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7))


def _wire_box(cx: float, cy: float, z0: float, yaw: float, length: float, width: float, height: float
              ) -> list[Point3]:
    """The 12 edges of a box as a LineList (24 points)."""
    c, s = math.cos(yaw), math.sin(yaw)
    corners = []
    for z in (z0, z0 + height):
        for dx, dy in ((0.5, 0.5), (0.5, -0.5), (-0.5, -0.5), (-0.5, 0.5)):
            lx, ly = dx * length, dy * width
            corners.append((cx + c * lx - s * ly, cy + s * lx + c * ly, z))
    return [Point3(x=corners[i][0], y=corners[i][1], z=corners[i][2]) for e in _BOX_EDGES for i in e]


def truth_update(scene, view, t_s: float, *, mount_z_m: float = 0.5) -> SceneUpdate:
    """The scenario's actors at ``t_s`` (``view``: :meth:`Scene.view`) as wire-frame boxes in the ``radar`` frame.

    One entity per actor, ``id`` ``"truth <actor id>"``, with metadata: class, centre (m), speed over ground
    and relative velocity (m/s, sensor axes), range to the nearest point (m).
    """
    ts = stamp(t_s)
    entities = []
    for i, actor in enumerate(scene.actors):
        length, width = float(scene.length_m[i]), float(scene.width_m[i])
        height = float(scene.height_m[i])                    # the scenario's: a bridge's deck, a gantry's panels
        bottom = float(scene.z_m[i]) - mount_z_m
        cx, cy, yaw = float(view.centre_x_m[i]), float(view.centre_y_m[i]), float(view.orientation_rad[i])
        meta = {"actor": actor.id, "class": actor.object_class, "centre_x_m": cx, "centre_y_m": cy,
                "speed_mps": float(math.hypot(view.ground_vx_mps[i], view.ground_vy_mps[i])),
                "vrel_x_mps": float(view.vx_mps[i]), "vrel_y_mps": float(view.vy_mps[i]),
                "range_m": float(math.hypot(view.x_m[i], view.y_m[i]))}
        entities.append(SceneEntity(
            timestamp=ts, frame_id=RADAR, id=f"truth {actor.id}", metadata=_kv(meta),
            lines=[LinePrimitive(type=LinePrimitiveLineType.LineList, pose=_pose(0.0, 0.0, 0.0), thickness=0.08,
                                 points=_wire_box(cx, cy, bottom, yaw, length, width, height),
                                 color=_color(TRUTH_RGB, 0.9))],
            texts=[TextPrimitive(pose=_pose(cx, cy, bottom + height + 0.3), billboard=True, font_size=11.0,
                                 scale_invariant=True, color=_color(TRUTH_RGB, 0.8), text=actor.id)]))
    return SceneUpdate(deletions=[SceneEntityDeletion(timestamp=ts, type=SceneEntityDeletionType.All)],
                       entities=entities)


def road_update(scene, t_s: float, stamp_s: float, *, range_m: float, mount_z_m: float = 0.5, step_m: float = 2.0
                ) -> SceneUpdate:
    """The scenario's lane lines (grey) and guardrails (white) ahead of the ego at scenario time ``t_s``, in the
    ``radar`` frame, stamped ``stamp_s``."""
    ts = stamp(stamp_s)
    road = scene.scenario.road
    lines = []
    for k in range(road.lanes + 1):
        d = road.right_edge_y_m + k * road.lane_width_m
        lines.append((f"lane line {k}", d, (0.6, 0.6, 0.6), 0.0))
    g = road.guardrails
    if g.left_offset_m is not None:
        lines.append(("guardrail left", road.left_edge_y_m + g.left_offset_m, (1.0, 1.0, 1.0), 0.5))
    if g.right_offset_m is not None:
        lines.append(("guardrail right", road.right_edge_y_m - g.right_offset_m, (1.0, 1.0, 1.0), 0.5))
    entities = []
    for ident, d, rgb, z in lines:
        x, y = scene.road_line(t_s, d, range_m, step_m)
        entities.append(SceneEntity(
            timestamp=ts, frame_id=RADAR, id=ident, metadata=_kv({"offset_m": d}),
            lines=[LinePrimitive(type=LinePrimitiveLineType.LineStrip, pose=_pose(0.0, 0.0, 0.0), thickness=0.12,
                                 points=[Point3(x=float(a), y=float(b), z=z - mount_z_m) for a, b in zip(x, y)],
                                 color=_color(rgb, 0.8))]))
    return SceneUpdate(entities=entities)


def transforms(ego, mount, t_s: float) -> FrameTransforms:
    """``world`` → ``ego`` (the ego's pose, :class:`EgoState`) and ``ego`` → ``radar`` (``mount``: x_m, y_m,
    z_m, yaw_deg)."""
    ts = stamp(t_s)
    return FrameTransforms(transforms=[
        FrameTransform(timestamp=ts, parent_frame_id=WORLD, child_frame_id=EGO,
                       translation=Vector3(x=ego.x_m, y=ego.y_m, z=0.0), rotation=_yaw(ego.heading_rad)),
        FrameTransform(timestamp=ts, parent_frame_id=EGO, child_frame_id=RADAR,
                       translation=Vector3(x=float(mount.x_m), y=float(mount.y_m), z=float(mount.z_m)),
                       rotation=_yaw(math.radians(float(mount.yaw_deg))))])


def ego_update(length_m: float, width_m: float, t_s: float, *, rear_overhang_m: float = 1.0,
               height_m: float = 1.5) -> SceneUpdate:
    """The ego vehicle as a grey box in the ``ego`` frame (origin at the rear axle, ``rear_overhang_m`` behind it)."""
    ts = stamp(t_s)
    cube = CubePrimitive(pose=_pose(0.5 * length_m - rear_overhang_m, 0.0, 0.5 * height_m),
                         size=Vector3(x=length_m, y=width_m, z=height_m), color=_color((0.55, 0.55, 0.6), 0.9))
    return SceneUpdate(entities=[SceneEntity(timestamp=ts, frame_id=EGO, id="ego", cubes=[cube])])


def range_doppler_image(rd_power: np.ndarray, range_bin_m: float, max_range_m: float, t_s: float
                        ) -> tuple[RawImage, dict]:
    """The range–Doppler map as an rgb8 image: Doppler across (closing on the left), range up (far at the top).

    ``rd_power`` has shape (doppler, range), Doppler fftshifted. Colour: viridis over the top
    :data:`RD_FLOOR_DB` dB of the map, relative to its strongest cell, with the R⁴ spreading taken out (as
    ``radarnode image`` draws it). Returns the image and its scales (``range_bin_m``, ``rows`` …) for the caption.
    """
    m, n = rd_power.shape
    n_keep = max(1, min(n, int(math.ceil(max_range_m / range_bin_m)) + 1))
    ranges = np.arange(n_keep) * range_bin_m
    db = 10.0 * np.log10(rd_power[:, :n_keep] + 1e-30) + 40.0 * np.log10(np.maximum(ranges, 2.0))[None, :]
    rel = np.clip((db - db.max()) / -RD_FLOOR_DB + 1.0, 0.0, 1.0)          # 0 at the floor, 1 at the peak
    img = rel.T[::-1, :]                                                  # (range, doppler), far range first
    pos = img * (len(VIRIDIS) - 1)
    lo = np.minimum(pos.astype(np.int64), len(VIRIDIS) - 2)
    frac = (pos - lo)[..., None]
    rgb = (VIRIDIS[lo] * (1.0 - frac) + VIRIDIS[lo + 1] * frac)
    data = np.ascontiguousarray((rgb * 255.0 + 0.5).astype(np.uint8))
    image = RawImage(timestamp=stamp(t_s), frame_id=RADAR, width=m, height=n_keep, encoding="rgb8", step=3 * m,
                     data=data.tobytes())
    return image, {"rows": n_keep, "columns": m, "range_bin_m": range_bin_m, "top_range_m": float(ranges[-1])}


def range_doppler_annotations(scales: dict, doppler_bin_mps: float, t_s: float) -> ImageAnnotations:
    """The scales of :func:`range_doppler_image` drawn on it (pixel coordinates, origin top left): range at the
    top and bottom rows, range rate at the left edge, zero and the right edge, the zero-speed column as a
    line, and what the colour means."""
    rows, cols = scales["rows"], scales["columns"]
    half = cols // 2                                  # fftshifted: column M/2 is zero speed
    white, shade = _color((1.0, 1.0, 1.0)), _color((0.0, 0.0, 0.0), 0.5)
    size = max(4.0, round(cols / 22.0))

    def text(x: float, y: float, s: str, right: bool = False) -> TextAnnotation:
        if right:                                     # right-aligned: about 0.6 font sizes per character
            x = x - 0.62 * size * len(s)
        return TextAnnotation(timestamp=stamp(t_s), position=Point2(x=x, y=y), text=s, font_size=size,
                              text_color=white, background_color=shade)

    texts = [text(1.0, 1.0, f"{scales['top_range_m']:.0f} m"),
             text(1.0, rows - 2.2 * size, "0 m"),
             text(1.0, rows - 1.1 * size, f"{-half * doppler_bin_mps:+.1f} m/s"),
             text(half + 1.0, rows - 1.1 * size, "0"),
             text(cols - 1.0, rows - 1.1 * size, f"{(cols - 1 - half) * doppler_bin_mps:+.1f} m/s", right=True),
             text(cols - 1.0, 1.0, f"{RD_FLOOR_DB:.0f}…0 dB", right=True)]
    zero = PointsAnnotation(timestamp=stamp(t_s), type=PointsAnnotationType.LineStrip,
                            points=[Point2(x=half + 0.5, y=0.0), Point2(x=half + 0.5, y=float(rows))],
                            outline_color=_color((1.0, 1.0, 1.0), 0.35), thickness=0.5)
    return ImageAnnotations(texts=texts, points=[zero])


# --- radarnode's own JSON records -------------------------------------------------------------------------

CAN_FRAME_SCHEMA = {
    "title": "radarnode.CanFrame", "type": "object",
    "description": "One CAN frame as it was on the bus (or in the log)",
    "properties": {
        "timestamp": {"type": "number", "description": "s, as the frame carries it"},
        "channel": {"type": "string"},
        "can_id": {"type": "integer"},
        "can_id_hex": {"type": "string"},
        "message": {"type": "string", "description": "name in dbc/radarnode_bus.dbc, '' when unknown (and for an "
                    "extended-ID or CAN FD frame: the bus's messages are classical CAN frames with 11-bit IDs)"},
        "is_extended_id": {"type": "boolean"},
        "is_error_frame": {"type": "boolean"},
        "is_remote_frame": {"type": "boolean"},
        "is_fd": {"type": "boolean", "description": "a CAN FD frame (up to 64 data bytes), which no node of the "
                  "ARS 408's classical CAN bus sends: radarnode's node and consumer drop and count it"},
        "dlc": {"type": "integer", "description": "the data length in bytes (a remote frame: the length it asks for)"},
        "data": {"type": "string", "description": "payload, hex"},
    },
}

EGO_STATE_SCHEMA = {
    "title": "radarnode.EgoState", "type": "object",
    "description": "The ego's true motion (the scenario) and what the vehicle sent on the bus (0x300/0x301)",
    "properties": {
        "timestamp": {"type": "number", "description": "s"},
        "speed_mps": {"type": "number"}, "accel_mps2": {"type": "number"},
        "yaw_rate_dps": {"type": "number"},
        "x_m": {"type": "number"}, "y_m": {"type": "number"}, "heading_deg": {"type": "number"},
        "wire_speed_mps": {"type": ["number", "null"], "description": "decoded from SpeedInformation 0x300"},
        "wire_yaw_rate_dps": {"type": ["number", "null"], "description": "decoded from YawRateInformation 0x301"},
    },
}


def can_frame(msg: can.Message, name: str) -> dict:
    """One CAN frame as a JSON record (:data:`CAN_FRAME_SCHEMA`)."""
    return {"timestamp": float(msg.timestamp), "channel": "" if msg.channel is None else str(msg.channel),
            "can_id": int(msg.arbitration_id),
            "can_id_hex": f"0x{msg.arbitration_id:08X}" if msg.is_extended_id else f"0x{msg.arbitration_id:03X}",
            "message": name, "is_extended_id": bool(msg.is_extended_id), "is_error_frame": bool(msg.is_error_frame),
            "is_remote_frame": bool(msg.is_remote_frame), "is_fd": bool(msg.is_fd),
            "dlc": int(msg.dlc), "data": bytes(msg.data).hex().upper()}


def signal_schema(message) -> dict:
    """A JSON Schema for a decoded cantools message: one number per signal (its unit in the description), and
    ``<signal>_label`` text for signals with a value table."""
    props: dict = {"timestamp": {"type": "number", "description": "s, of the frame"}}
    for sig in message.signals:
        props[sig.name] = {"type": "number", "description": sig.unit or ""}
        if sig.choices:
            props[f"{sig.name}_label"] = {"type": "string", "enum": sorted({str(v) for v in sig.choices.values()})}
    return {"title": f"radarnode.{message.name}", "type": "object",
            "description": f"decoded {message.name} 0x{message.frame_id:03X}", "properties": props}


def signal_record(message, values: dict, t_s: float) -> dict:
    """Decoded signal values (``decode_choices=False``) as a JSON record of :func:`signal_schema`."""
    rec: dict = {"timestamp": float(t_s)}
    for sig in message.signals:
        if sig.name not in values:
            continue
        v = signal_value(sig, values[sig.name])
        rec[sig.name] = v
        if sig.choices:
            rec[f"{sig.name}_label"] = str(sig.choices.get(int(v), "-"))
    return rec
