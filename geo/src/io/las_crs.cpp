// A LAS file's CRS records interpreted: WKT and GeoTIFF keys through crs.h, reconciled with
// the configured CRS.

#include "csgtile/geo/las.h"

namespace csgtile::geo {

namespace {

std::vector<GeoKeyEntry> geokey_entries(const LasCrsRecords& records) {
  std::vector<GeoKeyEntry> entries;
  entries.reserve(records.keys.size());
  for (const GeoKey& key : records.keys) {
    GeoKeyEntry e;
    e.id = key.id;
    if (key.location == 0) {
      e.numbers.push_back(key.value_offset);
    } else if (key.location == 34736) {
      e.numbers = key.doubles;
    } else if (key.location == 34737) {
      e.text = key.ascii;
    }
    entries.push_back(std::move(e));
  }
  return entries;
}

}  // namespace

kernel::Result<Crs> las_file_crs(const LasCrsRecords& records, std::string_view config,
                                 bool config_overrides_file) {
  CrsCandidates candidates;
  candidates.config_overrides_file = config_overrides_file;
  const std::optional<std::string>& wkt = records.wkt ? records.wkt : records.liblas_wkt;
  if (wkt && !wkt->empty()) candidates.wkt = crs_from_wkt(*wkt);
  if (records.has_geotiff && !records.keys.empty()) {
    candidates.geokeys = crs_from_geokeys(geokey_entries(records));
  }
  if (!config.empty()) candidates.config = crs_from_config(config);
  return reconcile_crs(candidates);
}

}  // namespace csgtile::geo
