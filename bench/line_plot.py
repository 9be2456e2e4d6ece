"""A minimal line plot written with Pillow (matplotlib is not a dependency of the project)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from PIL import Image, ImageDraw

COLOURS = ((31, 119, 180), (214, 39, 40), (44, 160, 44), (90, 90, 90), (148, 103, 189))
MARGIN = (70, 30, 20, 40)  # left, top, right, bottom


def _ticks(low: float, high: float, count: int = 5) -> np.ndarray:
    step = 10 ** np.floor(np.log10((high - low) / count))
    step *= min((m for m in (1, 2, 5, 10) if (high - low) / (m * step) <= count), default=10)
    return np.arange(np.ceil(low / step) * step, high + 1e-12, step)


def line_plot(path: str, x: np.ndarray, series: Sequence[tuple[str, np.ndarray]], title: str, x_label: str,
              y_label: str, size: tuple[int, int] = (900, 360)) -> None:
    """Draw every ``(label, y)`` of ``series`` against ``x`` into a PNG at ``path``."""
    image = Image.new("RGB", size, "white")
    draw = ImageDraw.Draw(image)
    left, top, right, bottom = MARGIN
    width, height = size[0] - left - right, size[1] - top - bottom
    values = np.concatenate([y for _, y in series])
    y_low, y_high = float(values.min()), float(values.max())
    pad = 0.05 * (y_high - y_low or 1.0)
    y_low, y_high = y_low - pad, y_high + pad
    x_low, x_high = float(x[0]), float(x[-1])

    def point(xv: np.ndarray, yv: np.ndarray) -> list[tuple[float, float]]:
        px = left + (xv - x_low) / (x_high - x_low) * width
        py = top + (y_high - yv) / (y_high - y_low) * height
        return list(zip(px.tolist(), py.tolist(), strict=True))

    draw.rectangle([left, top, left + width, top + height], outline=(0, 0, 0))
    for tick in _ticks(y_low, y_high):
        (_, py), = point(np.array([x_low]), np.array([tick]))
        draw.line([left - 4, py, left, py], fill=(0, 0, 0))
        draw.text((4, py - 6), f"{0.0 if abs(tick) < 1e-12 else tick:.3g}", fill=(0, 0, 0))
    for tick in _ticks(x_low, x_high):
        (px, _), = point(np.array([tick]), np.array([y_low]))
        draw.line([px, top + height, px, top + height + 4], fill=(0, 0, 0))
        draw.text((px - 8, top + height + 8), f"{tick:.3g}", fill=(0, 0, 0))
    stride = max(1, len(x) // (2 * width))
    for i, (label, y) in enumerate(series):
        colour = COLOURS[i % len(COLOURS)]
        draw.line(point(x[::stride], y[::stride]), fill=colour, width=2 if i < 3 else 1)
        draw.text((left + 10 + 170 * i, 8), label, fill=colour)
    draw.text((left + width // 2 - 40, size[1] - 18), x_label, fill=(0, 0, 0))
    draw.text((left + width - 8 * len(title), top + 4), title, fill=(0, 0, 0))
    draw.text((4, top - 24), y_label, fill=(0, 0, 0))
    image.save(path)
