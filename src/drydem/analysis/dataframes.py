"""Results as pandas DataFrames: :func:`data_frame`, with which every result's ``to_dataframe``
makes its table (pandas is optional: imported there only)."""

from __future__ import annotations

import copy

from drydem.errors import DrydemError


def data_frame(columns: dict[str, list], attrs: dict):
    """``columns`` (name: one value per row) as a pandas DataFrame whose ``attrs`` are a deep copy
    of ``attrs`` (what the rows do not hold: a result's own lists, which editing the frame must
    not change). pandas, an optional dependency (``pip install 'drydem[data]'``),
    is imported here only; DrydemError saying how to install it when it is missing."""
    try:
        import pandas
    except ImportError:
        raise DrydemError("a DataFrame needs pandas, which is not installed: pip install pandas (or pip install 'drydem[data]')") from None
    frame = pandas.DataFrame(columns)
    frame.attrs.update(copy.deepcopy(attrs))
    return frame
