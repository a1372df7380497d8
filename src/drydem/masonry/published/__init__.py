"""Published numbers drydem compares itself with.

``savalle2022.json``: the tables of Savalle, Lourenco & Milani (2022), Applied Sciences 12, 2108
(experimental collapse angles and their CoV, limit analysis, 3DEC results at several kn).
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path


@cache
def savalle2022() -> dict:
    return json.loads((Path(__file__).parent / "savalle2022.json").read_text())
