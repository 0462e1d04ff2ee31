#include "hivecal/core/status.hpp"

namespace hivecal {

const char* status_message(Status status) {
  switch (status) {
    case Status::ok: return "ok";
    case Status::non_finite_input: return "input contains NaN or Inf";
    case Status::invalid_argument: return "argument out of range";
    case Status::dataset_full: return "dataset is full (capacity reached)";
    case Status::dataset_empty: return "dataset is empty";
    case Status::too_few_samples: return "too few samples for this operation";
    case Status::degenerate_geometry: return "degenerate geometry (points collinear or coincident)";
    case Status::not_converged: return "solver did not converge";
    case Status::singular_system: return "singular linear system";
    case Status::buffer_too_small: return "output buffer too small";
    case Status::frame_too_long: return "frame longer than the decoder buffer";
    case Status::cobs_error: return "malformed COBS frame";
    case Status::bad_length: return "packet length does not match its type";
    case Status::bad_crc: return "CRC-32C mismatch";
    case Status::bad_version: return "unsupported packet version";
    case Status::unknown_type: return "unknown packet type";
    case Status::clock_fit_failed: return "clock relation could not be estimated";
    case Status::bad_payload: return "packet padding or name bytes not as specified";
    case Status::population_out_of_range: return "population size out of range";
    case Status::dimension_out_of_range: return "problem dimension out of range";
    case Status::bad_bounds: return "search bounds not finite or not increasing";
    case Status::poses_not_distinct: return "all samples at the same joint positions";
    case Status::solver_cancelled: return "solver cancelled by its observer";
    case Status::read_failed: return "reading the byte stream failed";
    case Status::joint_count_mismatch: return "joint readings of another joint count than the robot model";
  }
  return "unknown status";
}

}  // namespace hivecal
