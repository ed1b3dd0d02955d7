// Terrain rasters for mpmsdem::TerrainSpec: the ESRI ASCII grid (.asc), the plain-text elevation
// raster GIS tools export (GDAL's "AAIGrid"). GeoTIFF and the other formats GDAL reads come in
// through the Python package (mpmsdem.terrain), which hands their heights over as arrays.
#pragma once
#include <string>
#include <vector>

namespace mpmsdem {
namespace io {

// A raster of heights with its georeference: node (i, j), 0 <= i < nx (columns, west to east),
// 0 <= j < ny (rows, south to north), at (x0 + i spacing, y0 + j spacing) with height
// heights[i * ny + j] (the layout of mpmsdem::TerrainSpec).
struct TerrainRaster {
  int nx = 0, ny = 0;
  double x0 = 0, y0 = 0;  // centre of the south-west cell, in the file's coordinates [m]
  double spacing = 0;     // cell size [m]
  std::vector<double> heights;
};

// Reads an ESRI ASCII grid: the header keys ncols, nrows, xllcorner or xllcenter, yllcorner or
// yllcenter, cellsize and optionally NODATA_value (any case, any order), then nrows rows of ncols
// heights from the north row to the south one. The heights are taken at the cell centres (a
// corner-registered header is moved by half a cell). Throws ParameterError naming the file and
// what is wrong: missing or repeated key, ncols or nrows below 2, cellsize not > 0, too few or
// too many values, a value that is not a number, and no-data nodes (their count and the first
// one's column and row: fill them before using the raster as a terrain).
TerrainRaster readEsriAscii(const std::string& path);

}  // namespace io
}  // namespace mpmsdem
