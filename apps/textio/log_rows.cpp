#include "textio/log_rows.hpp"

#include "hivecal/port/error.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {

bool TimeOrder::accept(std::uint64_t t_us, bool* repeated, std::string* problem) {
  if (started_ && t_us < last_us_) {
    *problem = "timestamp " + format_double(static_cast<double>(t_us) * 1e-6) + " s does not increase (previous " +
               format_double(static_cast<double>(last_us_) * 1e-6) + " s)";
    return false;
  }
  *repeated = started_ && t_us == last_us_;
  started_ = true;
  last_us_ = t_us;
  return true;
}

bool map_joints_by_name(const std::vector<std::string_view>& names, const std::array<std::string, kSixJoints>& expected,
                        int source[kSixJoints]) {
  bool all = true;
  for (std::size_t j = 0; j < expected.size(); ++j) {
    source[j] = -1;
    for (std::size_t k = 0; k < names.size() && source[j] < 0; ++k) {
      if (names[k] == expected[j]) source[j] = static_cast<int>(k);
    }
    all = all && source[j] >= 0;
  }
  return all;
}

std::string join_names(const std::vector<std::string_view>& names) {
  std::string out;
  for (const std::string_view n : names) out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

std::string missing_joints_message(const std::string& file, const std::array<std::string, kSixJoints>& expected,
                                   const std::string& names_found) {
  return file + ": no message names all of the joints " +
         join_names(std::vector<std::string_view>(expected.begin(), expected.end())) + "; the log names " +
         port::quoted(names_found, 200) + " (give the robot's joint names)";
}

}  // namespace hivecal::textio
