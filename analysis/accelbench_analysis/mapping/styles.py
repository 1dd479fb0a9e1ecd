"""One colour per structure, the same in every figure.

Styles are assigned by order, benchopt-style, never looked up in a hand-kept table that a new
structure can miss: the structure table's variants (structures.py, the registry's order)
take the first places, so BVH (median) has the same colour in every figure of every run;
any other structure the data holds (a newly registered accelerator, a label the analysis
does not know) takes the next free place in order of first appearance. Every place has its
own colour, so no structure is drawn in a default black and no two share a colour; the
baseline (the table's role `baseline`, Embree) is grey.

Every figure colours by the structure table's label of a row ("wide BVH (8, SIMD)"),
never by accelerator name.
"""

from __future__ import annotations

import colorsys
from collections.abc import Iterable

from .structures import table_labels

# Matplotlib's tab10 without its grey (kept for Embree, the baseline) and tab20's lighter
# halves after it: distinct hues first, then the lighter variants.
_BASE = [
    "#1f77b4",  # blue
    "#ff7f0e",  # orange
    "#2ca02c",  # green
    "#9467bd",  # purple
    "#d62728",  # red
    "#17becf",  # cyan
    "#8c564b",  # brown
    "#e377c2",  # pink
    "#bcbd22",  # olive
    "#aec7e8",
    "#ffbb78",
    "#98df8a",
    "#c5b0d5",
    "#ff9896",
    "#9edae5",
    "#c49c94",
    "#f7b6d2",
    "#dbdb8d",
]
BASELINE_COLOUR = "#7f7f7f"


def known_labels() -> list[str]:
    """The structure table's labels of the comparison's structures, in its order."""
    return table_labels()


def baseline_labels() -> set[str]:
    return set(table_labels(("baseline",)))


def _extra_colour(i: int) -> str:
    """Colours past the table: evenly spaced hues, darker than the table's light halves."""
    h = (i * 0.618033988749895) % 1.0
    r, g, b = colorsys.hls_to_rgb(h, 0.42, 0.75)
    return f"#{int(r * 255):02x}{int(g * 255):02x}{int(b * 255):02x}"


def colour_at(place: int) -> str:
    return _BASE[place] if place < len(_BASE) else _extra_colour(place - len(_BASE))


def structure_order(labels: Iterable[str]) -> list[str]:
    """The labels present, known structures first in registry order, then the others in
    order of first appearance."""
    seen = list(dict.fromkeys(str(x) for x in labels))
    known = known_labels()
    return [k for k in known if k in seen] + [x for x in seen if x not in known]


class Styles:
    """Colours for one figure's labels. Known structures keep their place across
    figures; unknown labels take places after every known one. Embree, the baseline row,
    is grey."""

    def __init__(self, labels: Iterable[str]):
        self.order = structure_order(labels)
        self.baseline = baseline_labels()
        coloured = [k for k in known_labels() if k not in self.baseline]
        unknown = iter(range(len(coloured), len(coloured) + len(self.order)))
        self.places = {
            label: coloured.index(label) if label in coloured else next(unknown)
            for label in self.order
            if label not in self.baseline
        }

    def colour(self, label: str) -> str:
        return BASELINE_COLOUR if label in self.baseline else colour_at(self.places[label])

    def palette(self) -> dict[str, str]:
        return {label: self.colour(label) for label in self.order}
