// Footprints through GDAL/OGR (see footprints.h): open the source, pick the layer and the id
// field, filter by the target bbox carried back into the layer's CRS, reproject each feature's
// polygons, keep them in feature order. This file is the GDAL module (libcsgtile_gdal.so),
// loaded by footprints.cpp on the first read; see gdal_module.h.

#include "footprints/gdal_module.h"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <memory>
#include <mutex>

namespace csgtile::geo {

namespace {

using kernel::ErrorCode;

std::string last_gdal_error() {
  const char* m = CPLGetLastErrorMsg();
  return m != nullptr && *m != '\0' ? std::string(m) : std::string("no reason given");
}

// GDAL's name for a source: http(s) URLs are read through its curl file system.
std::string gdal_name(const std::string& source) {
  if (source.rfind("http://", 0) == 0 || source.rfind("https://", 0) == 0)
    return "/vsicurl/" + source;
  return source;
}

struct TransformDeleter {
  void operator()(OGRCoordinateTransformation* t) const {
    OGRCoordinateTransformation::DestroyCT(t);
  }
};
using Transform = std::unique_ptr<OGRCoordinateTransformation, TransformDeleter>;

std::vector<kernel::Vec2> ring_points(const OGRLinearRing& ring) {
  std::vector<kernel::Vec2> out;
  const int n = ring.getNumPoints();
  out.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) out.emplace_back(ring.getX(i), ring.getY(i));
  if (out.size() > 1 && out.front() == out.back()) out.pop_back();
  return out;
}

// The polygons of a (multi)polygon, or a reason why there are none.
std::string polygons_of(const OGRGeometry& g, std::vector<FootprintPolygon>& out) {
  const OGRwkbGeometryType type = wkbFlatten(g.getGeometryType());
  if (type == wkbPolygon) {
    const auto& poly = *g.toPolygon();
    if (poly.IsEmpty() || poly.getExteriorRing() == nullptr) return "an empty polygon";
    FootprintPolygon p;
    p.outer = ring_points(*poly.getExteriorRing());
    if (p.outer.size() < 3) return "an outer ring of fewer than 3 points";
    for (int h = 0; h < poly.getNumInteriorRings(); ++h) {
      auto hole = ring_points(*poly.getInteriorRing(h));
      if (hole.size() >= 3) p.holes.push_back(std::move(hole));
    }
    out.push_back(std::move(p));
    return {};
  }
  if (type == wkbMultiPolygon || type == wkbGeometryCollection) {
    const auto& coll = *g.toGeometryCollection();
    for (int k = 0; k < coll.getNumGeometries(); ++k) {
      if (auto why = polygons_of(*coll.getGeometryRef(k), out); !why.empty()) return why;
    }
    return out.empty() ? "an empty multipolygon" : std::string();
  }
  if (type == wkbCurvePolygon || type == wkbMultiSurface) {
    std::unique_ptr<OGRGeometry> linear(g.getLinearGeometry());
    if (linear) return polygons_of(*linear, out);
  }
  return std::string("a ") + OGRGeometryTypeToName(g.getGeometryType()) + " is no polygon";
}

// The polygons among a geometry's parts; lines and points (where a footprint only touches
// the box it was cut to) are no part of it.
void polygon_parts(const OGRGeometry& g, std::vector<FootprintPolygon>& out) {
  const OGRwkbGeometryType type = wkbFlatten(g.getGeometryType());
  if (g.IsEmpty()) return;
  if (type == wkbMultiPolygon || type == wkbGeometryCollection) {
    const auto& coll = *g.toGeometryCollection();
    for (int k = 0; k < coll.getNumGeometries(); ++k) polygon_parts(*coll.getGeometryRef(k), out);
  } else if (type == wkbPolygon) {
    std::vector<FootprintPolygon> one;
    if (polygons_of(g, one).empty()) out.insert(out.end(), one.begin(), one.end());
  }
}

// An axis-aligned box as a polygon.
std::unique_ptr<OGRPolygon> box_polygon(const std::array<double, 4>& b) {
  auto rect = std::make_unique<OGRPolygon>();
  OGRLinearRing ring;
  ring.addPoint(b[0], b[1]);
  ring.addPoint(b[2], b[1]);
  ring.addPoint(b[2], b[3]);
  ring.addPoint(b[0], b[3]);
  ring.addPoint(b[0], b[1]);
  rect->addRing(&ring);
  return rect;
}

// The union of boxes (one box: itself); null when GEOS fails.
std::unique_ptr<OGRGeometry> union_of_boxes(const std::vector<std::array<double, 4>>& boxes) {
  if (boxes.size() == 1) return box_polygon(boxes.front());
  OGRMultiPolygon all;
  for (const auto& b : boxes) all.addGeometryDirectly(box_polygon(b).release());
  CPLErrorReset();
  return std::unique_ptr<OGRGeometry>(all.UnionCascaded());
}

// The geometry cut to a region; null when GEOS fails (last_gdal_error says why).
std::unique_ptr<OGRGeometry> cut_to(const OGRGeometry& g, const OGRGeometry& region) {
  CPLErrorReset();
  return std::unique_ptr<OGRGeometry>(g.Intersection(&region));
}

kernel::Result<FootprintSet> read_with_gdal(const FootprintSource& source,
                                            const FootprintQuery& query) {
  static std::once_flag registered;
  std::call_once(registered, [] { GDALAllRegister(); });
  const std::string what = "footprints " + source.source;
  if (source.source.empty()) return kernel::Error{ErrorCode::InvalidArgument, what + ": no source"};
  // GDAL's messages go into ours (CPLGetLastErrorMsg), not to stderr; the handler stack is
  // the calling thread's.
  struct Quiet {
    Quiet() { CPLPushErrorHandler(CPLQuietErrorHandler); }
    ~Quiet() { CPLPopErrorHandler(); }
  } quiet;
  CPLErrorReset();
  GDALDatasetUniquePtr ds(GDALDataset::Open(gdal_name(source.source).c_str(),
                                            GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr,
                                            nullptr));
  if (!ds) {
    return kernel::Error{ErrorCode::IoError,
                         what + ": GDAL cannot open it as a vector source: " + last_gdal_error()};
  }
  auto layer_names = [&] {
    std::string names;
    for (auto* l : ds->GetLayers())
      names += (names.empty() ? "" : ", ") + std::string(l->GetName());
    return names.empty() ? std::string("none") : names;
  };
  OGRLayer* layer = nullptr;
  if (source.layer.empty()) {
    if (ds->GetLayerCount() != 1) {
      return kernel::Error{ErrorCode::InvalidArgument,
                           what + ": has " + std::to_string(ds->GetLayerCount()) +
                               " layers, name one (city.footprints_layer): " + layer_names()};
    }
    layer = ds->GetLayer(0);
  } else {
    layer = ds->GetLayerByName(source.layer.c_str());
    if (layer == nullptr) {
      return kernel::Error{ErrorCode::InvalidArgument, what + ": no layer '" + source.layer +
                                                           "'; its layers: " + layer_names()};
    }
  }
  FootprintSet out;
  out.layer = layer->GetName();
  OGRFeatureDefn* defn = layer->GetLayerDefn();
  int id_field = -1;
  if (!source.id_attribute.empty()) {
    id_field = defn->GetFieldIndex(source.id_attribute.c_str());
    if (id_field < 0) {
      std::string fields;
      for (int k = 0; k < defn->GetFieldCount(); ++k)
        fields += (k == 0 ? "" : ", ") + std::string(defn->GetFieldDefn(k)->GetNameRef());
      return kernel::Error{
          ErrorCode::InvalidArgument,
          what + ": layer " + out.layer + " has no attribute '" + source.id_attribute +
              "'; its attributes: " + (fields.empty() ? std::string("none") : fields)};
    }
  }
  // Source and target CRS; x = easting (longitude) in both, whatever the CRS's axis order.
  const OGRSpatialReference* layer_srs = layer->GetSpatialRef();
  Transform to_target, to_source;
  if (layer_srs != nullptr) {
    char* wkt = nullptr;
    if (layer_srs->exportToWkt(&wkt) == OGRERR_NONE && wkt != nullptr) out.source_crs = wkt;
    CPLFree(wkt);
  }
  if (!query.target_crs.empty() && layer_srs != nullptr) {
    OGRSpatialReference target;
    if (target.SetFromUserInput(query.target_crs.c_str()) != OGRERR_NONE) {
      return kernel::Error{ErrorCode::InvalidArgument,
                           what + ": GDAL cannot read the target CRS " + query.target_crs};
    }
    if (target.IsCompound()) target.StripVertical();
    target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    OGRSpatialReference from(*layer_srs);
    if (from.IsCompound()) from.StripVertical();
    from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    if (!from.IsSame(&target)) {
      CPLErrorReset();
      to_target.reset(OGRCreateCoordinateTransformation(&from, &target));
      to_source.reset(OGRCreateCoordinateTransformation(&target, &from));
      if (!to_target || !to_source) {
        return kernel::Error{ErrorCode::InvalidArgument,
                             what + ": no transformation from the layer's CRS to " +
                                 query.target_crs + ": " + last_gdal_error()};
      }
    }
  }
  if (query.check_only) return out;
  if (query.bbox) {
    double x0 = (*query.bbox)[0], y0 = (*query.bbox)[1], x1 = (*query.bbox)[2],
           y1 = (*query.bbox)[3];
    if (to_source) {
      double a0 = 0, b0 = 0, a1 = 0, b1 = 0;
      if (!to_source->TransformBounds(x0, y0, x1, y1, &a0, &b0, &a1, &b1, 21)) {
        return kernel::Error{ErrorCode::InvalidArgument,
                             what + ": the tile's bounds do not reproject to the layer's CRS"};
      }
      x0 = a0, y0 = b0, x1 = a1, y1 = b1;
    }
    layer->SetSpatialFilterRect(x0, y0, x1, y1);
  } else {
    layer->SetSpatialFilter(nullptr);
  }
  std::unique_ptr<OGRGeometry> clip_region, cut_region;
  if (!query.clip.empty()) {
    clip_region = union_of_boxes(query.clip);
    if (!clip_region) {
      return kernel::Error{ErrorCode::InvalidArgument,
                           what + ": the region to cut footprints to: " + last_gdal_error()};
    }
  }
  if (query.cut) cut_region = box_polygon(*query.cut);
  layer->ResetReading();
  for (auto& feature : *layer) {
    const std::string fid = std::to_string(feature->GetFID());
    Footprint fp;
    fp.id = id_field >= 0 ? std::string(feature->GetFieldAsString(id_field)) : fid;
    const std::string name =
        "feature " + fid + (id_field >= 0 ? " (" + source.id_attribute + " " + fp.id + ")" : "");
    OGRGeometry* geometry = feature->GetGeometryRef();
    if (geometry == nullptr || geometry->IsEmpty()) {
      out.skipped.push_back(name + ": no geometry");
      continue;
    }
    if (to_target && geometry->transform(to_target.get()) != OGRERR_NONE) {
      out.skipped.push_back(name + ": does not reproject: " + last_gdal_error());
      continue;
    }
    OGREnvelope e;
    geometry->getEnvelope(&e);
    fp.envelope = {e.MinX, e.MinY, e.MaxX, e.MaxY};
    if (query.bbox) {
      const auto& b = *query.bbox;
      if (e.MaxX < b[0] || e.MinX > b[2] || e.MaxY < b[1] || e.MinY > b[3]) continue;
    }
    std::unique_ptr<OGRGeometry> clipped;
    if (auto why = polygons_of(*geometry, fp.polygons); !why.empty()) {
      out.skipped.push_back(name + ": " + why);
      continue;
    }
    if (clip_region) {
      clipped = cut_to(*geometry, *clip_region);
      if (!clipped) {
        out.skipped.push_back(name + ": cannot be cut to the bounds: " + last_gdal_error());
        continue;
      }
      // Its polygons inside the region; lines and points where it only touches it are none.
      fp.polygons.clear();
      polygon_parts(*clipped, fp.polygons);
      if (fp.polygons.empty()) continue;
      geometry = clipped.get();
    }
    if (query.cut) {
      const std::unique_ptr<OGRGeometry> part = cut_to(*geometry, *cut_region);
      if (part) {
        polygon_parts(*part, fp.cut);
      } else {
        out.skipped.push_back(name + ": cannot be cut to the tile (no part of it is made here): " +
                              last_gdal_error());
      }
    }
    out.footprints.push_back(std::move(fp));
  }
  return out;
}

}  // namespace

}  // namespace csgtile::geo

// The module's entry points (gdal_module.h): C names, so that dlsym finds them.
extern "C" __attribute__((visibility("default"))) const char* csgtile_module_abi() {
  return csgtile::geo::kGdalModuleAbi;
}

extern "C" __attribute__((visibility("default"))) void csgtile_gdal_read_footprints(
    const csgtile::geo::FootprintSource& source, const csgtile::geo::FootprintQuery& query,
    csgtile::kernel::Result<csgtile::geo::FootprintSet>& out) noexcept {
  // Nothing thrown crosses the module's C boundary: an exception (memory exhausted in GDAL)
  // is the read's error, and `out` keeps the caller's error when even that cannot be made.
  try {
    out = csgtile::geo::read_with_gdal(source, query);
  } catch (const std::exception& e) {
    try {
      out = csgtile::kernel::Error{csgtile::kernel::ErrorCode::IoError,
                                   "footprints " + source.source + ": GDAL threw: " + e.what()};
    } catch (...) {
      // out keeps the caller's error
    }
  } catch (...) {
    // out keeps the caller's error
  }
}
