// The names of the job's methods, stages, solvers, steps and verdicts, and the significance
// level of a parameter (calibration.hpp).
#include <cmath>
#include <cstring>

#include "job/job.hpp"

namespace hivecal {
namespace {

/// Every method and its name: the one table of both directions, in the order of the help.
struct MethodName {
  CalibrationMethod method;
  const char* name;
};
constexpr MethodName kMethodNames[] = {
    {CalibrationMethod::abc_lm, "abc+lm"}, {CalibrationMethod::gsa_lm, "gsa+lm"}, {CalibrationMethod::lm, "lm"},
    {CalibrationMethod::abc, "abc"},       {CalibrationMethod::gsa, "gsa"},       {CalibrationMethod::all, "all"},
};

}  // namespace

const char* calibration_method_name(CalibrationMethod method) {
  for (const MethodName& entry : kMethodNames)
    if (entry.method == method) return entry.name;
  return "unknown";
}

const char* calibration_method_names() {
  return "abc+lm, gsa+lm, lm, abc, gsa, all";
}

Status calibration_method_from_name(const char* name, CalibrationMethod* method) {
  if (name == nullptr || method == nullptr) return Status::invalid_argument;
  for (const MethodName& entry : kMethodNames) {
    if (std::strcmp(entry.name, name) == 0) {
      *method = entry.method;
      return Status::ok;
    }
  }
  return Status::invalid_argument;
}

const char* blunder_verdict_name(BlunderVerdict verdict) {
  switch (verdict) {
    case BlunderVerdict::not_searched: return "not_searched";
    case BlunderVerdict::clean: return "clean";
    case BlunderVerdict::removed: return "removed";
    case BlunderVerdict::model_error: return "model_error";
    case BlunderVerdict::list_full: return "list_full";
    case BlunderVerdict::at_threshold: return "at_threshold";
    case BlunderVerdict::prediction_error: return "prediction_error";
  }
  return "unknown";
}

double parameter_significance_level(const RobotModel& model, int index, double significance_t, double compliance_t,
                                    int dof) {
  if (index < rigid_param_count(model)) return significance_t;
  return std::fmax(significance_t, joint_term_levels(model, compliance_t, dof).of(index));
}

const char* calibration_solver_name(CalibrationSolver solver) {
  switch (solver) {
    case CalibrationSolver::abc: return "ABC";
    case CalibrationSolver::gsa: return "GSA";
    case CalibrationSolver::lm: return "LM";
  }
  return "unknown";
}

const char* calibration_stage_name(const CalibrationStage& stage, const CalibrationStage* previous) {
  if (stage.compliance) return joint_term_stage_name(joint_term_families_of(stage.model.compliance));
  if (stage.solver != CalibrationSolver::lm || !stage.refines_previous || previous == nullptr) {
    return calibration_solver_name(stage.solver);
  }
  return previous->solver == CalibrationSolver::abc ? "ABC+LM" : "GSA+LM";
}

const char* calibration_step_name(CalibrationStep step) {
  switch (step) {
    case CalibrationStep::input: return "input";
    case CalibrationStep::split: return "split";
    case CalibrationStep::baseline: return "baseline";
    case CalibrationStep::gsa: return "gsa";
    case CalibrationStep::abc: return "abc";
    case CalibrationStep::lm: return "lm";
    case CalibrationStep::done: return "done";
  }
  return "unknown";
}

}  // namespace hivecal
