// XYZ text: one point per line, "x y z [more columns]" separated by blanks or commas; '#'
// starts a comment; an optional first line of column names. Columns after z that are named
// after a Point field (intensity, classification, red/green/blue or r/g/b as 8-bit values,
// nx/ny/nz, ...) fill it; all others become float64 extra dimensions ("column_4", ... or
// their header names).

#include <algorithm>
#include <cmath>
#include <cstring>

#include "io/endian.h"
#include "io/readers.h"

namespace csgtile::geo::detail {

namespace {

using kernel::Error;
using kernel::ErrorCode;

// The line without its comment.
std::string_view strip_comment(std::string_view line) {
  const auto hash = line.find('#');
  if (hash != std::string_view::npos) line = line.substr(0, hash);
  if (line.starts_with("//")) return {};
  return trim(line);
}

class XyzReader final : public PointReader {
 public:
  XyzReader(std::string name, PointCloudInfo info, PointReadOptions options,
            std::unique_ptr<ByteSource> source, std::uint64_t data_start,
            std::vector<PointTarget> targets, std::vector<int> extra_slot, bool commas)
      : PointReader(std::move(name), std::move(info), options),
        source_(std::move(source)),
        lines_(*source_, data_start),
        targets_(std::move(targets)),
        extra_slot_(std::move(extra_slot)),
        commas_(commas) {}

 protected:
  kernel::Result<std::size_t> read_records(PointBatch& batch, std::size_t max) override {
    const std::size_t stride = batch.extra_record_size();
    batch.clear();
    std::string_view line;
    while (batch.points.size() < max) {
      auto more = lines_.next_line(line);
      if (!more.ok()) return more.error();
      if (!more.value()) break;
      line = strip_comment(line);
      if (line.empty()) continue;
      const auto tokens = split_fields(line, commas_);
      if (tokens.size() != targets_.size()) {
        return Error{ErrorCode::CorruptData,
                     name() + ": line " + std::to_string(lines_.line_number()) + " has " +
                         std::to_string(tokens.size()) + " columns, expected " +
                         std::to_string(targets_.size()) + " like the first data line"};
      }
      Point p;
      batch.points.push_back(p);
      batch.extra_bytes.resize(batch.extra_bytes.size() + stride, 0);
      Point& q = batch.points.back();
      for (std::size_t c = 0; c < tokens.size(); ++c) {
        const auto value = parse_number<double>(tokens[c]);
        if (!value) {
          return Error{ErrorCode::CorruptData,
                       name() + ": line " + std::to_string(lines_.line_number()) + ", column " +
                           std::to_string(c + 1) + ": \"" + std::string(tokens[c].substr(0, 40)) +
                           "\" is not a number"};
        }
        if (extra_slot_[c] >= 0) {
          std::uint8_t* at = batch.extra_bytes.data() + batch.extra_bytes.size() - stride +
                             8 * static_cast<std::size_t>(extra_slot_[c]);
          store_le<double>(at, *value);
        } else {
          assign_target(q, targets_[c], *value, true);
        }
      }
    }
    return batch.points.size();
  }

 private:
  std::unique_ptr<ByteSource> source_;
  SequentialReader lines_;
  std::vector<PointTarget> targets_;
  std::vector<int> extra_slot_;  // per column: index of its float64 extra dimension, or -1
  bool commas_;
};

}  // namespace

kernel::Result<std::unique_ptr<PointReader>> open_xyz(std::unique_ptr<ByteSource> source,
                                                      const PointReadOptions& options) {
  const std::string name = source->name();
  SequentialReader lines(*source, 0);
  std::string_view line;
  std::uint64_t first_data = 0;
  std::vector<std::string> names;
  bool commas = false;
  bool header = false;
  std::size_t columns = 0;
  // Find the first line with content: column names or the first point.
  for (;;) {
    const std::uint64_t start = lines.position();
    auto more = lines.next_line(line);
    if (!more.ok()) return more.error();
    if (!more.value()) break;
    line = strip_comment(line);
    if (line.empty()) continue;
    commas = line.find(',') != std::string_view::npos;
    const auto tokens = split_fields(line, commas);
    const bool numeric = std::all_of(tokens.begin(), tokens.end(), [](std::string_view t) {
      return parse_number<double>(t).has_value();
    });
    columns = tokens.size();
    if (numeric) {
      first_data = start;
    } else {
      header = true;
      for (auto t : tokens) names.emplace_back(t);
      first_data = lines.position();
    }
    break;
  }
  if (columns == 0 && !header) {
    // An empty file is a valid cloud of no points.
    columns = 3;
  }
  if (columns < 3) {
    return Error{ErrorCode::CorruptData,
                 name + ": the first " + std::string(header ? "(header) " : "") + "line has " +
                     std::to_string(columns) + " columns; XYZ text needs at least x y z"};
  }
  std::vector<PointTarget> targets(columns, PointTarget::None);
  std::vector<int> extra_slot(columns, -1);
  PointCloudInfo info;
  info.format = PointFileFormat::Xyz;
  info.description = std::string("XYZ text, ") + std::to_string(columns) + " columns" +
                     (header ? " with a header line" : "");
  auto layout = std::make_shared<ExtraLayout>();
  bool has_xyz[3] = {false, false, false};
  for (std::size_t c = 0; c < columns; ++c) {
    PointTarget t = PointTarget::None;
    if (header) {
      t = point_target(names[c]);
      if (t == PointTarget::Rgb) t = PointTarget::None;  // a packed colour is not text
    } else if (c < 3) {
      t = static_cast<PointTarget>(static_cast<int>(PointTarget::X) + static_cast<int>(c));
    }
    if (t == PointTarget::X || t == PointTarget::Y || t == PointTarget::Z) {
      const int axis = static_cast<int>(t) - static_cast<int>(PointTarget::X);
      if (has_xyz[axis])
        t = PointTarget::None;  // a repeated name: keep the first
      else
        has_xyz[axis] = true;
    }
    targets[c] = t;
    if (t == PointTarget::None) {
      ExtraDimension d;
      d.name = header ? names[c] : "column_" + std::to_string(c + 1);
      d.type = ExtraType::F64;
      d.byte_offset = layout->record_size;
      extra_slot[c] = static_cast<int>(layout->dimensions.size());
      layout->record_size += 8;
      layout->dimensions.push_back(std::move(d));
    } else {
      mark_field(info.fields, t);
    }
  }
  if (header && !(has_xyz[0] && has_xyz[1] && has_xyz[2])) {
    return Error{ErrorCode::CorruptData, name +
                                             ": the header line names no x, y and z columns (\"" +
                                             std::string(trim(line)).substr(0, 80) + "\")"};
  }
  if (!layout->dimensions.empty()) info.extra = std::move(layout);
  std::unique_ptr<PointReader> reader =
      std::make_unique<XyzReader>(name, std::move(info), options, std::move(source), first_data,
                                  std::move(targets), std::move(extra_slot), commas);
  return reader;
}

}  // namespace csgtile::geo::detail
