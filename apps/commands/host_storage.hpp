// Storage of a command's calibration that grows with its input. The library stays heap-free:
// its datasets and workspaces are size-erased views over storage of the caller's; on the host
// that storage comes from the heap, sized to the input (any set that fits in memory).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "hivecal/calibration.hpp"
#include "hivecal/model/dataset.hpp"

namespace hivecal::cli {

/// A dataset that doubles its heap storage when full (DatasetBase::grow).
class HostDataset final : public DatasetBase {
 public:
  HostDataset() : DatasetBase(nullptr, 0) {}

 protected:
  bool grow(std::size_t needed) override {
    std::vector<Sample> next(std::max({needed, 2 * storage_.size(), kFirstRoom}));
    if (!move_to(next.data(), next.size())) return false;
    storage_.swap(next);
    return true;
  }

 private:
  static constexpr std::size_t kFirstRoom = 1024;  // samples
  std::vector<Sample> storage_;
};

/// The calibration job's workspace over a heap arena sized for the dataset at hand.
template <std::size_t TraceCapacity>
class HostWorkspace {
 public:
  using View = CalibrationWorkspaceView<150, TraceCapacity>;  ///< the paper's 150 food sources / agents

  /// The workspace with room for `samples` samples (the arena grows, never shrinks).
  View& for_samples(std::size_t samples) {
    samples = std::max<std::size_t>(samples, 1);
    const std::size_t bytes = View::arena_bytes(samples);
    if (arena_.size() * sizeof(std::max_align_t) < bytes) {
      arena_.assign((bytes + sizeof(std::max_align_t) - 1) / sizeof(std::max_align_t), std::max_align_t{});
    }
    const Span<unsigned char> room(reinterpret_cast<unsigned char*>(arena_.data()),
                                   arena_.size() * sizeof(std::max_align_t));
    (void)view_.attach(room, samples);  // cannot fail: aligned, large enough, samples > 0
    return view_;
  }

 private:
  std::vector<std::max_align_t> arena_;
  View view_;
};

}  // namespace hivecal::cli
