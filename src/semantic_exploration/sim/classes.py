"""Semantic class table of the simulator, mirroring the C++ ``semexp::ClassTable``.

Class id = index in ``names`` + 1; 0 means "no / unknown class". Scene labels
that are not in the table (wall, floor, window ...) are background.
"""

from typing import Iterable, List, Optional

#: Default class names, same order as include/semantic_exploration/core/class_table.hpp.
DEFAULT_CLASS_NAMES = ["chair", "table", "sofa", "bed", "cabinet",
                       "plant", "tv_monitor", "backpack", "keyboard", "cushion"]

#: Default classes of interest (paper: chair).
DEFAULT_OF_INTEREST = ["chair"]

#: Labels whose surfaces return no depth (a ToF/stereo camera sees through or
#: is deflected by them).
DEFAULT_NON_RETURNING = ["window", "mirror"]

#: mpcat40 category indices (Matterport3D) for the labels the generator writes.
#: Names absent from mpcat40 (backpack, keyboard) use 39 "objects" there.
MPCAT40_INDEX = {
    "void": 0, "wall": 1, "floor": 2, "chair": 3, "door": 4, "table": 5, "picture": 6,
    "cabinet": 7, "cushion": 8, "window": 9, "sofa": 10, "bed": 11, "curtain": 12,
    "chest_of_drawers": 13, "plant": 14, "sink": 15, "stairs": 16, "ceiling": 17,
    "toilet": 18, "stool": 19, "towel": 20, "mirror": 21, "tv_monitor": 22, "shower": 23,
    "column": 24, "bathtub": 25, "counter": 26, "fireplace": 27, "lighting": 28,
    "beam": 29, "railing": 30, "shelving": 31, "blinds": 32, "gym_equipment": 33,
    "seating": 34, "board_panel": 35, "furniture": 36, "appliances": 37, "clothes": 38,
    "objects": 39, "misc": 40, "unlabeled": 41,
}


class ClassTable:
    """Known classes and classes of interest."""

    def __init__(self, names: Optional[Iterable[str]] = None,
                 of_interest: Optional[Iterable[str]] = None):
        self.names: List[str] = list(DEFAULT_CLASS_NAMES if names is None else names)
        self.of_interest: List[str] = list(DEFAULT_OF_INTEREST if of_interest is None else of_interest)
        self.validate()

    def validate(self, ns: str = "classes/") -> None:
        from .config import ConfigError
        if not self.names:
            raise ConfigError(ns + "names", "must list at least one class")
        if len(set(self.names)) != len(self.names):
            raise ConfigError(ns + "names", "duplicate class name")
        if any(not isinstance(n, str) or not n for n in self.names):
            raise ConfigError(ns + "names", "class names must be non-empty strings")
        if len(self.names) >= 65535:
            raise ConfigError(ns + "names", "at most 65534 classes (16-bit ids)")
        for n in self.of_interest:
            if n not in self.names:
                raise ConfigError(ns + "of_interest", "unknown class '%s' (not in %snames)" % (n, ns))

    def id(self, name: str) -> int:
        """Class id of ``name``; 0 if unknown."""
        try:
            return self.names.index(name) + 1
        except ValueError:
            return 0

    def name(self, class_id: int) -> str:
        return self.names[class_id - 1] if 1 <= class_id <= len(self.names) else ""

    def is_of_interest(self, class_id: int) -> bool:
        n = self.name(class_id)
        return bool(n) and n in self.of_interest
