"""Convert an ESRI ASCII elevation grid (or a crop of it) to a GeoTIFF, e.g. for a site file's DEM.

    python scripts/tools/convert_dem.py IN.asc OUT.tif [--crs EPSG:4326] [--crop X0,X1,Y0,Y1]

``--crop`` keeps the grid points with x in [X0, X1] and y in [Y0, Y1] (the grid's own coordinates: longitude
and latitude for a geographic grid); ``--crs`` is the grid's CRS (an ASCII grid has none of its own; default
EPSG:4326, WGS84 longitude/latitude). The bundled site's DEM was made with::

    python scripts/tools/convert_dem.py /work/shared/data/terrain/srtm_front_range_144.asc \\
        sites/front_range/dem.tif --crop=-105.49,-105.435,40.170,40.215
"""

from __future__ import annotations

import argparse
import sys

from drd_planner.exceptions import DrdError
from drd_planner.geometry.geotiff import crop_heightfield, read_geotiff, write_geotiff
from drd_planner.geometry.terrain import read_esri_ascii


def _box(text: str) -> tuple[float, float, float, float]:
    try:
        x0, x1, y0, y1 = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give X0,X1,Y0,Y1") from None
    if not (x0 < x1 and y0 < y1):
        raise argparse.ArgumentTypeError(f"{text!r}: need X0 < X1 and Y0 < Y1")
    return x0, x1, y0, y1


def main(argv: list[str] | None = None) -> int:
    """Convert; errors print one line and exit 2."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("source", help="ESRI ASCII grid (.asc)")
    parser.add_argument("out", help="GeoTIFF to write (.tif)")
    parser.add_argument("--crs", default="EPSG:4326", help="the grid's CRS (default EPSG:4326)")
    parser.add_argument("--crop", type=_box, metavar="X0,X1,Y0,Y1", help="keep only this box (grid coordinates)")
    args = parser.parse_args(argv)
    try:
        grid = read_esri_ascii(args.source)
        if args.crop is not None:
            x0, x1, y0, y1 = args.crop
            grid = crop_heightfield(grid, (x0, x1), (y0, y1))
        write_geotiff(args.out, grid, args.crs)
        back, header = read_geotiff(args.out)
    except DrdError as exc:
        print(f"convert_dem: error: {exc}", file=sys.stderr)
        return 2
    rows, cols = back.heights.shape
    x0, x1, y0, y1 = header.bounds
    print(f"wrote {args.out}: {rows} x {cols} cells of {header.cell:g}, x [{x0:.6f}, {x1:.6f}], y [{y0:.6f}, {y1:.6f}]")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
