"""The Foxglove layout shipped with radarnode: ``layouts/foxglove_radarnode.json``, generated, never edited.

``python -m radarnode.viz.layout > layouts/foxglove_radarnode.json`` writes it; ``tests/test_foxglove.py`` fails
when the committed file is stale or names a topic the recorder does not write. The file is in the format the
Foxglove app exports and imports (Layouts → Import from file): panel configurations by ID (``configById``) and a
tree of splits (``layout``).

Panels: a 3-D view following the ego (the radar's objects as boxes, its clusters as points, the decoded road
boundaries, the ground truth as wire frames with the lane lines and guardrails, the ego); the range–Doppler map
(signal level); the ECU's ACC and FCW state over time (State Transitions); the ECU's request, TTC and the ego's
speed (Plot); the decoded object list and the raw CAN frames (Raw Messages).
"""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

LAYOUT_FILE = "foxglove_radarnode.json"


def layout_path() -> Path | None:
    """Where the layout file is: in the wheel (``radarnode/_layouts``) or the source tree (``layouts/``)."""
    packaged = resources.files("radarnode") / "_layouts" / LAYOUT_FILE
    if packaged.is_file():
        return Path(str(packaged))
    source = Path(__file__).resolve().parents[2] / "layouts" / LAYOUT_FILE
    return source if source.is_file() else None


def _three_d() -> dict:
    return {
        "cameraState": {"perspective": True, "distance": 90.0, "phi": 40.0, "thetaOffset": -90.0, "fovy": 45.0,
                        "near": 0.5, "far": 5000.0, "target": [0.0, 0.0, 0.0], "targetOffset": [45.0, 0.0, 0.0],
                        "targetOrientation": [0.0, 0.0, 0.0, 1.0]},
        "followMode": "follow-pose",
        "followTf": "ego",
        "scene": {"transforms": {"showLabel": False, "axisScale": 2.0}, "labelScaleFactor": 1.0},
        "transforms": {},
        "topics": {
            "/radar/objects": {"visible": True, "showOutlines": True},
            "/radar/clusters": {"visible": True, "pointSize": 8, "pointShape": "circle", "colorMode": "colormap",
                                "colorMap": "turbo", "colorField": "rcs_dbsm", "minValue": -20, "maxValue": 30},
            "/radar/road_boundaries": {"visible": True},
            "/ground_truth/actors": {"visible": True},
            "/ground_truth/road": {"visible": True},
            "/ego": {"visible": True},
        },
        "layers": {"grid": {"layerId": "foxglove.Grid", "instanceId": "grid", "label": "Grid (10 m)",
                            "visible": True, "frameId": "ego", "size": 300, "divisions": 30, "lineWidth": 1,
                            "color": "#ffffff30", "position": [130.0, 0.0, 0.0], "rotation": [0.0, 0.0, 0.0]}},
        "publish": {"type": "point", "poseTopic": "/move_base_simple/goal", "pointTopic": "/clicked_point",
                    "poseEstimateTopic": "/initialpose", "poseEstimateXDeviation": 0.5,
                    "poseEstimateYDeviation": 0.5, "poseEstimateThetaDeviation": 0.26},
        "imageMode": {},
    }


def _series(value: str, label: str) -> dict:
    return {"value": value, "label": label, "enabled": True, "timestampMethod": "receiveTime"}


def layout() -> dict:
    """The layout as a JSON-able dict."""
    config = {
        "3D!radarnode": _three_d(),
        "Image!range_doppler": {
            "imageMode": {"imageTopic": "/radar/range_doppler",
                          "annotations": {"/radar/range_doppler/annotations": {"visible": True}}},
            "cameraState": {}, "followMode": "follow-pose", "scene": {}, "transforms": {}, "topics": {},
            "layers": {}, "publish": {"type": "point"},
        },
        "StateTransitions!acc_fcw": {
            "paths": [_series("/ecu/acc.ACC_State_label", "ACC state"),
                      _series("/ecu/fcw.FCW_WarningLevel_label", "FCW warning"),
                      _series("/ecu/acc.ACC_TargetID", "ACC target ID")],
            "isSynced": True,
        },
        "Plot!acc_fcw": {
            "paths": [_series("/ecu/acc.ACC_AccelRequest", "ACC request, m/s²"),
                      _series("/ecu/fcw.FCW_TTC", "FCW TTC, s"),
                      _series("/ecu/acc.ACC_TimeGap", "ACC time gap, s"),
                      _series("/ego/state.speed_mps", "ego speed, m/s")],
            "showXAxisLabels": True, "showYAxisLabels": True, "showLegend": True, "legendDisplay": "floating",
            "showPlotValuesInLegend": True, "isSynced": True, "xAxisVal": "timestamp", "sidebarDimension": 240,
        },
        "RawMessages!objects": {"topicPath": "/radar/objects", "diffEnabled": False, "diffMethod": "custom",
                                "diffTopicPath": "", "showFullMessageForDiff": False, "expansion": "none"},
        "RawMessages!can": {"topicPath": "/can/frames", "diffEnabled": False, "diffMethod": "custom",
                            "diffTopicPath": "", "showFullMessageForDiff": False},
    }
    tree = {
        "direction": "row",
        "first": "3D!radarnode",
        "second": {
            "direction": "column",
            "first": {"direction": "row", "first": "Image!range_doppler", "second": "RawMessages!objects",
                      "splitPercentage": 50},
            "second": {
                "direction": "column",
                "first": "StateTransitions!acc_fcw",
                "second": {"direction": "row", "first": "Plot!acc_fcw", "second": "RawMessages!can",
                           "splitPercentage": 60},
                "splitPercentage": 35,
            },
            "splitPercentage": 45,
        },
        "splitPercentage": 55,
    }
    return {"configById": config, "globalVariables": {}, "userNodes": {}, "linkedGlobalVariables": [],
            "playbackConfig": {"speed": 1.0}, "layout": tree}


def topics_used(data: dict | None = None) -> set[str]:
    """Every topic the layout's panels read (the part of a message path before its first field)."""
    data = layout() if data is None else data
    out = set()
    for cfg in data["configById"].values():
        out.update(cfg.get("topics", {}))
        image = cfg.get("imageMode", {})
        if image.get("imageTopic"):
            out.add(image["imageTopic"])
        out.update(image.get("annotations", {}))
        for p in cfg.get("paths", []):
            out.add(p["value"].split(".", 1)[0])
        if "topicPath" in cfg:
            out.add(cfg["topicPath"].split(".", 1)[0])
    return out


def main() -> None:
    print(json.dumps(layout(), indent=2, ensure_ascii=False))


if __name__ == "__main__":
    main()
