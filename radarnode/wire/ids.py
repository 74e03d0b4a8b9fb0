"""radarnode's CAN ID plan: the ARS 408-21's IDs and radarnode's own messages beside them.

=================  ==============================  ==========================================
IDs                messages                        rule
=================  ==============================  ==========================================
0x200–0x27F …      ARS 408-21 (``dbc/ars408.dbc``)  base ID + 0x10 × SensorID (0x008 unshifted)
0x680–0x6BF        a sensor's own messages         0x680 + 8 × SensorID + slot (slot 0..7)
0x6C0–0x6FF        the consumer ECU's messages     0x6C0 + slot, one ECU per bus, not shifted
=================  ==============================  ==========================================

The ARS 408's highest shifted ID below 0x700 is 0x67E (Obj_4_Warning of sensor 7), so 0x680–0x6FF is
free on a bus with eight sensors. ``dbc/radarnode.dbc`` lists sensor 0's own messages (slot 0
RoadBoundary_Left 0x680, slot 1 RoadBoundary_Right 0x681) and the ECU's (AccStatus 0x6C0, FcwStatus
0x6C1): the template IDs used throughout the code.

Every own message is protected by AUTOSAR E2E Profile 2 with a Data ID that names the message *and*
the sensor (:func:`e2e_key`), so a frame of another sensor or another message that ends up on an ID
(a misconfigured node, a gateway) fails the CRC check.
"""

from __future__ import annotations

from radarnode.wire import ars408 as P

NUM_SENSORS = 8
OWN_FIRST, OWN_LAST = 0x680, 0x6FF
SENSOR_OWN_BASE, SENSOR_OWN_SLOTS = 0x680, 8
ECU_BASE, ECU_SLOTS = 0x6C0, 0x40

# template IDs (sensor 0), as in dbc/radarnode.dbc
ROAD_BOUNDARY_LEFT, ROAD_BOUNDARY_RIGHT = 0x680, 0x681
ACC_STATUS, FCW_STATUS = 0x6C0, 0x6C1


def _check_sensor(sensor_id: int) -> int:
    if isinstance(sensor_id, bool) or not isinstance(sensor_id, int) or not 0 <= sensor_id < NUM_SENSORS:
        raise ValueError(f"sensor_id: value {sensor_id!r} is not allowed; expected an integer 0..{NUM_SENSORS - 1}")
    return sensor_id


def is_sensor_message(template_id: int) -> bool:
    """True for a sensor's own message template (0x680–0x687), False for the ECU's (0x6C0–0x6FF)."""
    if SENSOR_OWN_BASE <= template_id < SENSOR_OWN_BASE + SENSOR_OWN_SLOTS:
        return True
    if ECU_BASE <= template_id < ECU_BASE + ECU_SLOTS:
        return False
    raise ValueError(f"template ID: value 0x{template_id:X} is not allowed; expected 0x{SENSOR_OWN_BASE:X}–"
                     f"0x{SENSOR_OWN_BASE + SENSOR_OWN_SLOTS - 1:X} (a sensor's own message) or "
                     f"0x{ECU_BASE:X}–0x{ECU_BASE + ECU_SLOTS - 1:X} (the ECU's)")


def own_id(template_id: int, sensor_id: int = 0) -> int:
    """The CAN ID of radarnode's own message ``template_id`` sent by (or for) sensor ``sensor_id``.

    A sensor's messages move by 8 per sensor ID; the ECU's are one per bus and ignore ``sensor_id``.
    """
    _check_sensor(sensor_id)
    if is_sensor_message(template_id):
        return template_id + SENSOR_OWN_SLOTS * sensor_id
    return template_id


def split_own_id(can_id: int) -> tuple[int, int | None] | None:
    """(template ID, sensor ID) of an own-range CAN ID; sensor ID None for the ECU's; None outside the range."""
    if OWN_FIRST <= can_id < ECU_BASE:
        sensor, slot = divmod(can_id - SENSOR_OWN_BASE, SENSOR_OWN_SLOTS)
        return SENSOR_OWN_BASE + slot, sensor
    if ECU_BASE <= can_id <= OWN_LAST:
        return can_id, None
    return None


def e2e_key(template_id: int, sensor_id: int = 0) -> int:
    """The E2E Profile 2 Data ID key of a message: 16 × SensorID + slot for a sensor's own messages
    (0x00–0x77), 0x80 + slot for the ECU's. Distinct for every (message, sensor), so the CRC of one
    never matches another's (the Data ID for counter c is ``(key + 17·c) mod 256``)."""
    _check_sensor(sensor_id)
    if is_sensor_message(template_id):
        return 0x10 * sensor_id + (template_id - SENSOR_OWN_BASE)
    return 0x80 + (template_id - ECU_BASE)


def ars408_id(base_id: int, sensor_id: int = 0) -> int:
    """The CAN ID of ARS 408 message ``base_id`` for sensor ``sensor_id`` (0x10 × SensorID shift)."""
    return P.shifted(base_id, _check_sensor(sensor_id))
