// Status codes returned by every fallible library call. The library never throws,
// never aborts on bad input and never returns a partial result with Status::ok.
#pragma once

#include <cstdint>

namespace hivecal {

/// What went wrong, or ok. Grouped by subsystem; names say which input was bad.
enum class Status : std::uint8_t {
  ok = 0,
  // Input values.
  non_finite_input,  ///< a NaN or Inf in joints, points, weights or parameters
  invalid_argument,  ///< a size, fraction or option outside its documented range
  // Datasets.
  dataset_full,     ///< capacity reached; the sample was not stored
  dataset_empty,    ///< an operation needs at least one sample
  too_few_samples,  ///< fewer samples than the operation needs (e.g. < 3 for a fit)
  // Geometry.
  degenerate_geometry,  ///< points (nearly) collinear or coincident: transform undetermined
  // Solvers.
  not_converged,    ///< iteration limit reached before the tolerance
  singular_system,  ///< normal equations not solvable even with damping
  // Codec.
  buffer_too_small,  ///< output buffer cannot hold the encoded frame
  frame_too_long,    ///< a frame exceeded the decoder buffer before its delimiter
  cobs_error,        ///< a COBS code byte pointed past the end of the frame
  bad_length,        ///< packet length does not match its type
  bad_crc,           ///< CRC-32C mismatch
  bad_version,       ///< version byte is not 1
  unknown_type,      ///< valid CRC but an unknown packet type (skipped, counted)
  // Sync.
  clock_fit_failed,  ///< not enough motion to relate the two clocks
  // Codec (added later, kept at the end so existing values do not move).
  bad_payload,  ///< valid CRC but padding not zero or device name not printable ASCII
  // Population solvers (ABC, GSA).
  population_out_of_range,  ///< population below the solver's minimum or above its capacity
  dimension_out_of_range,   ///< problem dimension 0, above capacity, or not matching the bounds
  bad_bounds,               ///< a search bound is NaN/Inf or lower >= upper
  // Levenberg-Marquardt calibration.
  poses_not_distinct,  ///< every sample was taken at the same joint positions: nothing to identify
  solver_cancelled,    ///< the progress observer asked the solver to stop
  // Stream input.
  read_failed,  ///< a byte source reported an I/O error
  // Joint counts (added with models of any joint count).
  joint_count_mismatch,  ///< joint records or samples of another joint count than the robot model
};

/// A short, stable, human-readable name for a status (for logs and CLI messages).
const char* status_message(Status status);

}  // namespace hivecal
