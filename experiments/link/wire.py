"""What crosses the link between a car and ``racf serve``: msgpack maps, numpy arrays as raw
buffers, read as untrusted input on both ends.

Every limit is stated once here: a message's size (also ZeroMQ's ``MAXMSGSIZE`` on both
sockets, so a larger one is cut off before it is read), msgpack's container and buffer
limits, the dtypes an array may have and the shape its bytes must fill. Anything else raises
:class:`WireError` with what was wrong, which the server answers as an error and the car counts
as a step without an answer: one path for every malformed message.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from racf.controllers import PerceptionSample
from racf.controllers.detector import Detection
from racf.controllers.existence import ExistenceWitnesses

__all__ = ["WireError", "InvalidAnswer", "MAX_MESSAGE_BYTES", "DEFAULT_TIMEOUT_MS", "DEFAULT_RETRY_S", "pack",
           "unpack", "encode_sample", "decode_sample", "PROTOCOL", "DISTANCE_RANGE_M", "MAX_REQUEST_ID",
           "wire_distance", "check_distance", "check_answer"]

#: The wire protocol's version: a server answers a hello from another version with an error, and a
#: car refuses a service that speaks another. 2: every request carries an id its answer names, and a
#: distance is a number in DISTANCE_RANGE_M or None (no target).
PROTOCOL = 2
#: The distance a defence may answer, m (the car's sensors see less than 50 m; ODCA's output is
#: NaN or within this range). Anything else is no answer.
DISTANCE_RANGE_M = (0.0, 50.0)
#: Request ids are counters below this (msgpack's int64).
MAX_REQUEST_ID = 2 ** 63 - 1
from racf.experiments.link.timing import DEFAULT_RETRY_S, DEFAULT_TIMEOUT_MS  # noqa: E402,F401  (their home)
#: The largest message either end reads. A step's sample is about 10 kB (a 320x240 mask,
#: bit-packed); a calibration less: 1 MiB leaves room for larger cameras and nothing more.
MAX_MESSAGE_BYTES = 1 << 20
#: msgpack's limits for untrusted input: no container or string needs more.
_LIMITS = {"max_str_len": 4096, "max_bin_len": MAX_MESSAGE_BYTES, "max_array_len": 4096, "max_map_len": 256,
           "max_ext_len": 0}
#: The arrays a message may carry (no objects, no void, nothing that executes on reading).
_DTYPES = frozenset(np.dtype(t).str for t in ("u1", "i4", "i8", "f4", "f8", "?"))


class WireError(ValueError):
    """A message that is not what the protocol allows (says what is wrong)."""


class InvalidAnswer(ValueError):
    """An answer the car must not act on. ``kind`` names the rule it broke (the car logs each kind
    once an episode): stale (it names another request), error, no_session, restarted (the service
    rebuilt its defence), protocol (another protocol's service), missing, wrong_type, out_of_range."""

    def __init__(self, kind: str, why: str) -> None:
        super().__init__(why)
        self.kind = kind


def _array(a: np.ndarray) -> dict:
    a = np.ascontiguousarray(a)
    return {"__nd__": True, "dtype": a.dtype.str, "shape": list(a.shape), "data": a.tobytes()}


def _default(obj: Any):
    if isinstance(obj, np.ndarray):
        return _array(obj)
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, tuple):
        return list(obj)
    raise TypeError(f"cannot send {type(obj).__name__} to the service")


def _hook(obj: dict):
    if not obj.get("__nd__"):
        return obj
    dtype, shape, data = obj.get("dtype"), obj.get("shape"), obj.get("data")
    if dtype not in _DTYPES:
        raise WireError(f"array dtype {dtype!r} is not allowed; allowed: {', '.join(sorted(_DTYPES))}")
    if not (isinstance(shape, list) and len(shape) <= 4 and all(isinstance(n, int) and 0 <= n for n in shape)):
        raise WireError(f"array shape {shape!r} is not a list of at most 4 sizes")
    if not isinstance(data, bytes) or len(data) != math.prod(shape) * np.dtype(dtype).itemsize:
        raise WireError(f"array of shape {shape} and dtype {dtype} does not match its {len(data or b'')} bytes")
    return np.frombuffer(data, dtype=np.dtype(dtype)).reshape(shape).copy()


def pack(message: dict) -> bytes:
    import msgpack

    return msgpack.packb(message, default=_default, use_bin_type=True)


def unpack(raw: bytes) -> dict:
    """One message: a map. Raises WireError for anything else (too large, not msgpack, over a limit,
    trailing bytes, a bad array)."""
    import msgpack

    if not isinstance(raw, (bytes, bytearray, memoryview)):
        raise WireError(f"a message is bytes, got {type(raw).__name__}")
    if len(raw) > MAX_MESSAGE_BYTES:
        raise WireError(f"message of {len(raw)} bytes; at most {MAX_MESSAGE_BYTES}")
    try:
        message = msgpack.unpackb(raw, object_hook=_hook, raw=False, strict_map_key=False, **_LIMITS)
    except WireError:
        raise
    except Exception as err:  # msgpack raises many kinds (ExtraData, FormatError, ValueError, ...): one answer
        raise WireError(f"not a msgpack message ({type(err).__name__}: {str(err)[:80]})") from None
    if not isinstance(message, dict):
        raise WireError(f"a message is a map, got {type(message).__name__}")
    return message


def encode_sample(sample: PerceptionSample) -> dict:
    """A sample as plain values and raw buffers (the detection's mask bit-packed)."""
    det = sample.detection
    out = {f.name: getattr(sample, f.name) for f in dataclasses.fields(sample) if f.name not in ("detection", "witnesses")}
    if det is not None:
        out["detection"] = {"mask": np.packbits(np.asarray(det.mask, bool)), "shape": list(det.mask.shape),
                            "box": list(det.box), "confidence": det.confidence, "area_px": det.area_px,
                            "centroid": list(det.centroid)}
    if sample.witnesses is not None:
        out["witnesses"] = dataclasses.asdict(sample.witnesses)
    return out


def decode_sample(raw: Any) -> PerceptionSample:
    """The sample ``encode_sample`` made; WireError for one that is not (missing or extra fields,
    wrong kinds, a mask whose bytes do not fill its shape)."""
    if not isinstance(raw, dict):
        raise WireError(f"a sample is a map, got {type(raw).__name__}")
    raw = dict(raw)
    det, wit = raw.pop("detection", None), raw.pop("witnesses", None)
    try:
        detection = None if det is None else _detection(det)
        witnesses = None
        if wit is not None:
            witnesses = ExistenceWitnesses(**{k: tuple(v) if isinstance(v, list) else v for k, v in wit.items()})
        sample = PerceptionSample(detection=detection, witnesses=witnesses, **raw)
    except WireError:
        raise
    except Exception as err:  # a field missing, one too many, a value of the wrong kind
        raise WireError(f"not a sample ({type(err).__name__}: {str(err)[:120]})") from None
    for f in dataclasses.fields(sample):
        value = getattr(sample, f.name)
        if f.name not in ("detection", "witnesses") and not isinstance(value, (int, float, bool, type(None))):
            raise WireError(f"sample field {f.name} must be a number, got {type(value).__name__}")
    return sample


def _detection(det: dict) -> Detection:
    h, w = (int(n) for n in det["shape"])
    if not (0 < h <= 4096 and 0 < w <= 4096):
        raise WireError(f"mask shape {det['shape']} outside 1..4096 a side")
    packed = det["mask"]
    if not isinstance(packed, np.ndarray) or packed.dtype != np.uint8 or packed.size != -(-h * w // 8):
        raise WireError(f"the mask's bits do not fill its shape {h}x{w}")
    mask = np.unpackbits(packed, count=h * w).reshape(h, w).astype(bool)
    return Detection(mask, tuple(int(v) for v in det["box"]), float(det["confidence"]), int(det["area_px"]),
                     tuple(float(v) for v in det["centroid"]))



def check_distance(distance) -> float | None:
    """A distance as the wire carries it: None (no target, said explicitly) or a finite number in
    DISTANCE_RANGE_M. InvalidAnswer for anything else, NaN and inf included: the car acts on no number
    the protocol does not allow, and the server sends none."""
    if distance is None:
        return None
    if not isinstance(distance, (int, float, np.floating, np.integer)) or isinstance(distance, (bool, np.bool_)):
        raise InvalidAnswer("wrong_type", f"a distance is a number or None, got {type(distance).__name__}")
    distance = float(distance)
    lo, hi = DISTANCE_RANGE_M
    if not lo <= distance <= hi:  # NaN fails this too: "no target" is None, never a NaN by accident
        raise InvalidAnswer("out_of_range", f"distance {distance!r} m is not a number in the protocol's "
                                            f"[{lo:g}, {hi:g}] m")
    return distance


def wire_distance(distance) -> float | None:
    """A defence's distance as the server sends it: its NaN (how defences say "no target") as None,
    anything else as :func:`check_distance` allows it."""
    if isinstance(distance, (float, np.floating)) and math.isnan(distance):
        return None
    return check_distance(distance)


def _optional_bool(value) -> bool | None:
    if value is not None and not isinstance(value, bool):
        raise InvalidAnswer("wrong_type", f"a verdict is true, false or None, got {type(value).__name__}")
    return value


def _bool(value) -> bool:
    if not isinstance(value, bool):
        raise InvalidAnswer("wrong_type", f"an answer is true or false, got {type(value).__name__}")
    return value


def _diagnostics(value) -> dict:
    if not isinstance(value, dict) or not all(isinstance(k, str) and isinstance(v, (int, float, str))
                                              for k, v in value.items()):
        raise InvalidAnswer("wrong_type", "diagnostics are a map of names to numbers or words")
    return value


def _protocol(value) -> int:
    if value != PROTOCOL:
        spoken = "1 (it names none)" if value is None else repr(value)
        raise InvalidAnswer("protocol", f"the service speaks protocol {spoken}; this car speaks {PROTOCOL}: run the "
                                        f"same racf on both ends")
    return value


#: What each request's answer must hold: field -> its check (a field not listed passes as it is).
_ANSWERS = {
    "ping": {"protocol": _protocol},
    "hello": {"protocol": _protocol},
    "estimate": {"distance": check_distance, "stands": _optional_bool, "diagnostics": _diagnostics},
    "would_pass": {"answer": _bool},
    "calibrate": {}, "reset": {}, "bye": {},
}


def check_answer(op: str, reply: dict, request_id: int) -> dict:
    """The answer to request ``request_id`` (an ``op``) with its fields checked, or InvalidAnswer
    naming the rule it broke. The one gate between what a service sends and what the car acts on."""
    if "protocol" in _ANSWERS[op] and "error" not in reply and "refused" not in reply:
        _protocol(reply.get("protocol"))  # first: another protocol's answers carry no ids
    if reply.get("id") != request_id or isinstance(reply.get("id"), bool):
        raise InvalidAnswer("stale", f"an answer to request {reply.get('id')!r}, not to request {request_id}")
    if "error" in reply:
        kind = "no_session" if reply.get("no_session") is True else "error"
        raise InvalidAnswer(kind, f"the service answered an error: {str(reply['error'])[:200]}")
    if "restarted" in reply:
        raise InvalidAnswer("restarted", f"the service rebuilt its defence: {str(reply['restarted'])[:200]}")
    if "refused" in reply:  # a hello it refused: the car is told why (not a step's answer)
        return reply
    out = dict(reply)
    for key, check in _ANSWERS[op].items():
        if key not in reply:
            raise InvalidAnswer("missing", f"an answer to {op} without {key}")
        out[key] = check(reply[key])
    return out
