#pragma once
// How far each object's points lie from its model, as 3DBAG measures its LoD2.2
// (b3_rmse_lod22): every point a fit job kept as the structures' (fit::FitOutput::
// structure_points) is published beside its scene (a points file), read back by the assemble
// job of each cell, given to the object it stands over and measured against that object's
// model — all of its points, not only those its primitives took as inliers.

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "city/city_internal.h"
#include "export/topology_index.h"

namespace csgtile::worker::city::detail {

/// The bytes of a points file: "CSGTPTS1", the count as a little-endian uint64, then x, y, z
/// of each point as little-endian float32 (the tile frame keeps them within a few km: about
/// 0.5 mm at 5 km).
std::string encode_points(std::span<const kernel::Vec3> points);
/// Reads a points file's bytes. Error: InputInvalid naming `what` (not a points file, or a
/// size that does not match its count).
Failure decode_points(std::string_view bytes, const std::string& what,
                      std::vector<kernel::Vec3>& out);

/// Per shape (null: none), its ModelFit: the points standing over it (the vertical line
/// through the point meets a non-vertical triangle of its mesh at `chordal_tolerance`), a
/// point over several shapes given to the nearest (the first on a tie); their RMS distance to
/// the shape's boundary and, where sigma[k] > 0, the share within 2 sigma[k]. Shapes without
/// points, or that cannot be meshed, get none. `over_none` receives the number of points over
/// no shape. Deterministic whatever the thread count (shapes are measured in parallel).
/// `meshes` (empty, or one per shape, null where absent): the shapes' tessellations at
/// `chordal_tolerance` when the caller has made them; the others are tessellated here.
std::vector<std::optional<ModelFit>> measure_model_fit(
    std::span<const kernel::Shape* const> shapes, std::span<const double> sigma,
    std::span<const kernel::Vec3> points, double chordal_tolerance, long long& over_none,
    std::span<const std::shared_ptr<const kernel::Mesh>> meshes = {});

/// A model fit as an object record keeps it ({"points", "rmse", "sigma", "within_2sigma"};
/// null for none), and read back (null or absent: none; Internal for a malformed one).
ordered_json model_fit_json(const std::optional<ModelFit>& fit);
Failure read_model_fit(const ordered_json& entry, std::optional<ModelFit>& out);

}  // namespace csgtile::worker::city::detail
