"""Input checks for signals and batch shapes, shared by the filters and the diagnosis examples."""

from __future__ import annotations

from typing import Any

import numpy as np

from course.validation import as_count, as_float_array


def _batch_shape(batch: Any) -> tuple:
    if batch is None:
        return ()
    if np.ndim(batch) == 0:
        batch = (batch,)
    return tuple(as_count(b, "batch", what="the number of independent runs") for b in batch)


def _as_signal(
    value, name: str, width: int, N: int | None = None, width_from: str = "the model"
) -> np.ndarray:
    """A signal of shape ``(*batch, N, width)``; ``(N,)`` is accepted when width is 1."""
    array = as_float_array(value, name, min_ndim=1)
    if array.ndim == 1:
        if width != 1:
            raise ValueError(
                f"{name} has shape {array.shape} but {width_from} has {width} channels; "
                f"pass an array of shape (N, {width}) or (batch, N, {width})"
            )
        array = array[:, None]
    if array.ndim < 2 or array.shape[-1] != width:
        raise ValueError(
            f"{name} must have shape (N, {width}) or (batch, N, {width}) for the {width} "
            f"channels of {width_from}, got {array.shape}"
        )
    if N is not None and array.shape[-2] != N:
        raise ValueError(f"{name} must have N = {N} samples along axis -2, got {array.shape[-2]}")
    if array.shape[-2] < 1:
        raise ValueError(f"{name} has no samples")
    return array
