"""What a viewer page embeds: its JSON data and the float32 arrays of its fields."""
from __future__ import annotations

import base64
import json
import re

import numpy as np

def page_data(path) -> dict:
    """The JSON the page's script reads."""
    text = path.read_text(encoding="utf-8")
    match = re.search(r'<script type="application/json" id="hht3d-data">(.*?)</script>', text, re.S)
    return json.loads(match.group(1))


def decoded(spec) -> np.ndarray:
    assert spec["dtype"] == "f4"
    return np.frombuffer(base64.b64decode(spec["bdata"]), dtype="<f4")


def field_values(data: dict, name: str, copy: int = 0) -> np.ndarray:
    return decoded(next(f for f in data["fields"] if f["name"] == name)["values"][copy])
