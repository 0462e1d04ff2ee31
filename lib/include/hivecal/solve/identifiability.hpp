// Which full-model parameters the samples can determine. From the eigen-decomposition of
// the column-scaled normal matrix J^T W J (eigenvalues = squared singular values of the
// column-scaled Jacobian) the null directions are found, and for each one the parameter
// with the largest component is dropped, i.e. held at its start value (docs/solver-lm.md).
#pragma once

#include <cstdint>

#include "hivecal/solve/normal_equations.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/linalg/symmetric_eigen.hpp"

namespace hivecal {

/// Default ratio sigma_k / sigma_max of the column-scaled Jacobian below which a direction
/// counts as not identifiable: exact null directions come out near 1e-8 (the square root
/// of double precision, as the normal matrix squares the Jacobian), directions that only a
/// sub-milliradian deviation from an ideal pose set excites near 1e-5, identifiable UR
/// directions above 1e-2 on a spread of poses.
inline constexpr double kDefaultIdentifiabilityThreshold = 1e-4;
/// Components of a null combination kept in a report entry.
inline constexpr int kNullComponentCount = 4;

/// Why a parameter was dropped.
enum class UnidentifiableReason : std::uint8_t {
  no_effect = 1,         ///< its Jacobian column is (nearly) zero: the samples do not see it
  null_combination = 2,  ///< a combination with other parameters leaves every residual unchanged
};

/// Lower-case name of a drop reason ("no_effect", "null_combination").
const char* unidentifiable_reason_name(UnidentifiableReason reason);

/// One dropped parameter and the combination that made it redundant.
struct DroppedParam {
  int index = -1;                                                 ///< the parameter (full_param_name)
  UnidentifiableReason reason = UnidentifiableReason::no_effect;  ///< why it was dropped
  double singular_ratio = 0.0;                                    ///< sigma of its direction / sigma_max [-]
  int component_index[kNullComponentCount] = {-1, -1, -1, -1};    ///< largest components, dropped one first; -1 unused
  double component[kNullComponentCount] = {};  ///< their coefficients (column-scaled units), dropped one = 1 [-]
};

/// Fixed-size result of the identifiability analysis.
struct IdentifiabilityReport {
  ParamMask free_mask = 0;                ///< parameters free by the options
  ParamMask kept_mask = 0;                ///< free and identifiable: the ones estimated
  int dropped_count = 0;                  ///< valid entries in dropped[]
  DroppedParam dropped[kFullParamCount];  ///< in the order they were dropped
  int singular_count_before = 0;          ///< valid entries of singular_values_before
  double singular_values_before[kFullParamCount] =
      {};                        ///< column-scaled J over the free parameters that have an effect, decreasing [-]
  int singular_count_after = 0;  ///< valid entries of singular_values_after
  double singular_values_after[kFullParamCount] = {};  ///< column-scaled J over the kept parameters, decreasing [-]
  double condition_before = 0.0;  ///< sigma_max / sigma_min before dropping [-] (Inf if sigma_min = 0)
  double condition_after = 0.0;   ///< sigma_max / sigma_min over the kept parameters [-]

  int kept_count() const { return mask_count(kept_mask); }  ///< parameters estimated
};

/// Resets every field of *report to its default, in place.
void clear_report(IdentifiabilityReport* report);

/// How much of the report analyze_identifiability must fill.
enum class IdentifiabilityOutput : std::uint8_t {
  report = 1,    ///< everything, both spectra included
  kept_set = 2,  ///< the kept set and the drops; the spectrum after dropping may be left out (a
                 ///< Cholesky certificate instead of its eigen-decomposition: singular_count_after 0)
};

/// Scratch memory of the analysis (27 kB): keep it static or in the caller's workspace.
struct IdentifiabilityWorkspace {
  NormalMatrix scaled;                ///< column-scaled normal matrix
  NormalMatrix rotated;               ///< copy of `scaled` reduced by symmetric_eigenvalues (keeps its reflections)
  NormalMatrix null_basis;            ///< eigenvectors of the null directions of `scaled`, reduced as parameters drop
  FullParams eigenvalues;             ///< of `scaled`, increasing (inactive parameters first, at -1)
  SymmetricEigenReduction reduction;  ///< tridiagonal form of `scaled`, for the null directions' eigenvectors
};

/// Analyses normal equations J^T W J (from accumulate_normal_equations) over the parameters
/// in `free_mask`: drops no-effect columns (norm below threshold * the largest diagonal
/// entry of all: accumulate the base translation columns too, whose norm sqrt(sum w) is
/// the physical reference), then null directions (sigma_k / sigma_max of the column-scaled
/// Jacobian below threshold), and fills *report.
/// A null direction drops the parameter with the largest component among those in
/// `drop_first` (the joint harmonics: generic terms, dropped before the physical ones they
/// mirror, e.g. a shoulder's gravity term), then among the rest in index order.
/// With `output` kept_set, the round that confirms a drop (no null direction left) is a
/// shifted Cholesky factorisation where it proves that, instead of an eigen-decomposition: the
/// same kept set and drops, without singular_values_after and condition_after.
/// Errors: invalid_argument (threshold not in (0, 1), empty or out-of-range mask),
/// non_finite_input, singular_system (no parameter left).
Status analyze_identifiability(const NormalMatrix& jtwj, ParamMask free_mask, double threshold,
                               IdentifiabilityWorkspace* workspace, IdentifiabilityReport* report,
                               ParamMask drop_first = 0, IdentifiabilityOutput output = IdentifiabilityOutput::report);

}  // namespace hivecal
