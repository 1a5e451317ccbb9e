"""The arena: occupancy maps, the map file format, and pose discretization."""

from skidnav.world.discretization import Discretization
from skidnav.world.grid import MAP_KINDS, GridMap, generate_map
from skidnav.world.mapfile import (
    MapFile,
    MapFileError,
    format_map,
    load_map,
    load_map_file,
    parse_map,
    parse_map_file,
    save_map,
)
from skidnav.world.maps import build_map

__all__ = [
    "MAP_KINDS",
    "Discretization",
    "GridMap",
    "MapFile",
    "MapFileError",
    "build_map",
    "format_map",
    "generate_map",
    "load_map",
    "load_map_file",
    "parse_map",
    "parse_map_file",
    "save_map",
]
