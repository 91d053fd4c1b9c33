#include "ops/stage_clock.h"

#include <algorithm>

#include "ops/metrics.h"

namespace csgtile::worker::ops {

void StageClock::enter(std::string_view stage) {
  if (stage_ == stage) return;
  stop();
  stage_ = stage;
  since_ = std::chrono::steady_clock::now();
}

void StageClock::stop() {
  if (stage_.empty()) return;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - since_).count();
  metrics().add_stage_seconds(stage_, seconds);
  if (out_) {
    auto& list = out_->seconds;
    auto it =
        std::find_if(list.begin(), list.end(), [&](const auto& p) { return p.first == stage_; });
    if (it == list.end()) {
      list.emplace_back(stage_, seconds);
    } else {
      it->second += seconds;
    }
  }
  stage_.clear();
}

}  // namespace csgtile::worker::ops
