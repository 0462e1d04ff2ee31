// hivecal calibrate: a run as the record result.json is written from (record/result_json.hpp).
#include <string>
#include <vector>

#include "commands/calibrate_parts.hpp"
#include "hivecal/calibration.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "record/result_json.hpp"

namespace hivecal::cli {

std::string calibration_result_json(const CalibrateSettings& settings, const report::ReportData& data,
                                    const streams::SessionFacts& facts, const Run& run,
                                    const std::vector<std::string>& warnings) {
  const CalibrationStage& final_stage = run.final_stage();
  record::CalibrationRecord record;
  record::CalibrationFile& file = record.file;
  static_cast<textio::RobotDescription&>(file) = settings.robot;  // name and convention as given
  file.model = final_stage.model;
  file.target_count = run.target_count;
  file.base_to_tracker = final_stage.base_to_tracker;
  file.has_metrics = true;
  file.metrics = data.calibrated;
  file.uncertainty = run.uncertainty;
  for (int t = 0; run.final_lm() != nullptr && t < final_stage.model.compliance.term_count; ++t) {
    const int k = compliance_param_index(final_stage.model, t);
    if (mask_has(run.final_lm()->identifiability.kept_mask, k)) file.compliance_sigma[t] = run.final_lm()->sigma(k);
  }
  record.method = run.final_method();
  record.params = settings.paper_params ? "paper" : "full";
  record.seed = settings.seed;
  record.split = settings.train_fraction;
  record.uncalibrated = data.uncalibrated;
  record.result = &run.result;
  record.final_lm = run.final_lm();
  record.joint_sigma_rad = settings.joint_sigma_rad;
  record.joint_sigma_position_sigma_m = settings.orientation.position_sigma_m;
  record.controller_tcp = settings.controller_tcp;
  record.ur_shape = has_ur_joints(settings.robot.model);
  if (record.ur_shape) record.ur_deltas = textio::ur_deltas_in_ur_table(settings.robot.model, final_stage.model);
  record.facts = &facts;
  record.cv = run.has_cv ? &run.cv : nullptr;
  for (const std::vector<std::uint32_t>& fold : run.cv_held_out)
    record.cv_held_out.push_back(held_out_ranges(facts, fold));
  record.cv_held_out_of = held_out_unit(facts);
  record.warnings = warnings;
  record.report = &data;
  return record::format_result_json(record);
}

}  // namespace hivecal::cli
