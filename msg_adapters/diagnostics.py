"""
diagnostic_msgs and std_msgs/Float64MultiArray builders and readers, duck-typed.

Message classes are passed in, so nothing here imports a message package. Conventions:

- KeyValue values are bare numbers (``repr`` of a float, so full precision; ints as ints;
  booleans as 1/0), the unit lives in the key (``bias_rad_s``): PlotJuggler and
  ``parse_key_values`` read them back as numbers.
- A Float64MultiArray is self-describing: each dimension label is ``name:item,item,...`` when
  its index has names (``channel:gyro_x,gyro_y``) or just ``name`` when it is a plain index.
  ``parse_multiarray`` returns the shaped array and the item names per dimension.
"""
import math
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

OK, WARN, ERROR, STALE = 0, 1, 2, 3


def format_value(value: Any) -> str:
    """One KeyValue value: a bare number when it is one, else ``str(value)``."""
    if isinstance(value, (bool, np.bool_)):
        return '1' if value else '0'
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return repr(value) if math.isfinite(value) else str(value).lower()
    return str(value)


def key_values(values: Mapping[str, Any], kv_cls: type) -> List[Any]:
    """Convert a dict to a list of KeyValue (insertion order kept)."""
    out = []
    for key, value in values.items():
        kv = kv_cls()
        kv.key = str(key)
        kv.value = format_value(value)
        out.append(kv)
    return out


def _level(status_cls: type, level: int) -> Any:
    # Jazzy's DiagnosticStatus.level is an octet (bytes of length 1); older ones use int.
    return bytes([level]) if isinstance(getattr(status_cls, 'OK', 0), bytes) else level


def level_of(status: Any) -> int:
    """DiagnosticStatus.level as an int whatever the binding's type."""
    lvl = status.level
    return lvl[0] if isinstance(lvl, (bytes, bytearray)) else int(lvl)


def diagnostic_status(status_cls: type, kv_cls: type, name: str, level: int, message: str,
                      hardware_id: str, values: Optional[Mapping[str, Any]] = None) -> Any:
    """Build one DiagnosticStatus."""
    status = status_cls()
    status.name = name
    status.level = _level(status_cls, level)
    status.message = message
    status.hardware_id = hardware_id
    status.values = key_values(values or {}, kv_cls)
    return status


def diagnostic_array(array_cls: type, stamp: Any, statuses: Sequence[Any]) -> Any:
    """Build a DiagnosticArray with ``stamp`` (a Time message) and the given statuses."""
    msg = array_cls()
    msg.header.stamp = stamp
    msg.status = list(statuses)
    return msg


def parse_value(text: str) -> Any:
    """Inverse of ``format_value``: int, float, or the string itself."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def parse_key_values(status: Any) -> Dict[str, Any]:
    """DiagnosticStatus.values -> dict with numbers parsed."""
    return {kv.key: parse_value(kv.value) for kv in status.values}


def multiarray(array_cls: type, dim_cls: type, data: np.ndarray,
               labels: Sequence[Tuple[str, Optional[Sequence[str]]]]) -> Any:
    """
    Build a row-major Float64MultiArray from an n-d array.

    ``labels`` has one ``(name, item_names or None)`` per dimension; item names, when given,
    must match the size of their dimension.
    """
    data = np.ascontiguousarray(data, dtype=np.float64)
    if len(labels) != data.ndim:
        raise ValueError(f'{len(labels)} labels for a {data.ndim}-d array')
    msg = array_cls()
    dims = []
    stride = data.size
    for (name, items), size in zip(labels, data.shape):
        if items is not None and len(items) != size:
            raise ValueError(f'dimension {name!r}: {len(items)} names for size {size}')
        if ':' in name or any(',' in i or ':' in i for i in items or ()):
            raise ValueError('labels must not contain ":" or ","')
        dim = dim_cls()
        dim.label = name if items is None else name + ':' + ','.join(items)
        dim.size = int(size)
        dim.stride = int(stride)
        stride = stride // size if size else 0
        dims.append(dim)
    msg.layout.dim = dims
    msg.layout.data_offset = 0
    msg.data = data.ravel().tolist()
    return msg


def parse_multiarray(msg: Any) -> Tuple[np.ndarray, List[Tuple[str, Optional[List[str]]]]]:
    """Float64MultiArray -> (shaped array, [(dimension name, item names or None), ...])."""
    shape = [int(d.size) for d in msg.layout.dim]
    labels = []
    for d in msg.layout.dim:
        name, _, items = d.label.partition(':')
        labels.append((name, items.split(',') if items else None))
    data = np.asarray(msg.data, dtype=np.float64)[msg.layout.data_offset:]
    return data[:int(np.prod(shape))].reshape(shape), labels
