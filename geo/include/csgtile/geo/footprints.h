#pragma once
/// \file
/// Building footprints from any vector source GDAL/OGR reads (GeoPackage, Shapefile,
/// FlatGeobuf, GeoJSON, SQLite, PostGIS "PG:..." connections, http(s) URLs), reprojected to
/// the run's CRS (issue #18 item 2). GDAL stays private to geo: nothing of it shows here.

#include <array>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "csgtile/kernel/location.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// One polygon: its outer ring, then its holes; rings open (the first point not repeated),
/// in the target CRS's x/y (easting, northing; longitude, latitude for geographic CRSs).
struct FootprintPolygon {
  std::vector<kernel::Vec2> outer;
  std::vector<std::vector<kernel::Vec2>> holes;
};

/// One building's footprint: the polygons of one feature (several for a multipolygon).
struct Footprint {
  std::string id;  ///< the id attribute's value, or the feature id when none was named
  std::vector<FootprintPolygon> polygons;
  /// With FootprintQuery::cut: the polygons cut to that box (empty when none is left).
  std::vector<FootprintPolygon> cut = {};
  /// The feature's envelope, reprojected, before any cut: [xmin, ymin, xmax, ymax].
  std::array<double, 4> envelope = {};
};

/// Where footprints come from.
struct FootprintSource {
  std::string source;        ///< a path, an http(s) URL, or a GDAL connection string
  std::string layer;         ///< "": the source's only layer (an error when it has several)
  std::string id_attribute;  ///< "": the feature id
};

/// What is read.
struct FootprintQuery {
  /// The CRS to reproject to, as crs_from_config reads it ("EPSG:28992", "EPSG:28992+5709",
  /// WKT); its horizontal part is used. "": the coordinates as stored.
  std::string target_crs;
  /// Only features whose reprojected envelope meets [xmin, ymin, xmax, ymax] (target CRS).
  std::optional<std::array<double, 4>> bbox;
  /// Their polygons cut to the union of these boxes (a run's buildings end where its data
  /// ends); none: as they are.
  std::vector<std::array<double, 4>> clip = {};
  /// Also gives each footprint's polygons cut to [xmin, ymin, xmax, ymax] (Footprint::cut),
  /// beside its polygons as they are (a tile's part of a building larger than its halo).
  std::optional<std::array<double, 4>> cut = {};
  /// Only check: open the source, find the layer and the attribute, make the transformation;
  /// read no feature (a run's configuration checked before its jobs start).
  bool check_only = false;
};

struct FootprintSet {
  std::vector<Footprint> footprints;  ///< in the layer's feature order
  /// Features that give no footprint, each with its reason ("feature 12: no geometry",
  /// "feature 40 (id 0363...): a LINESTRING is no polygon"): none is dropped silently.
  std::vector<std::string> skipped;
  std::string layer;       ///< the layer read
  std::string source_crs;  ///< the layer's CRS as WKT, "" when it has none
};

/// Loads the GDAL module read_footprints needs on a thread of its own, so that a process
/// about to read footprints does other work (a CRS from PROJ's database) meanwhile instead of
/// waiting for it (binding GDAL and its libraries takes about 0.08 s). The thread joins when
/// it goes out of scope; an empty thread when none can be started (the first read loads it).
std::jthread load_footprints_in_background();

/// Reads the footprints. A source without a CRS is taken to be in the target CRS. Errors
/// (IoError for sources that cannot be opened, InvalidArgument otherwise) name the source and
/// what is wrong: no such layer (listing the layers), no such attribute (listing the
/// fields), a target CRS GDAL cannot read, no transformation between the CRSs.
kernel::Result<FootprintSet> read_footprints(const FootprintSource& source,
                                             const FootprintQuery& query);

}  // namespace csgtile::geo
