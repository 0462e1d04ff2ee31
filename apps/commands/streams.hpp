// `hivecal record` (serial ports -> capture files) and `hivecal extract` (capture files ->
// clock relation -> quasi-static samples CSV), docs/streams.md.
#pragma once

namespace hivecal::streams {

inline constexpr const char* kRecordCommand = "record";    ///< the subcommands' names, as typed after `hivecal`
inline constexpr const char* kExtractCommand = "extract";  ///< and shown in their messages

/// Entry point of `hivecal record` (argv after the command name); returns the exit code.
int record_main(int argc, char** argv);
/// Entry point of `hivecal extract` (argv after the command name); returns the exit code.
int extract_main(int argc, char** argv);

}  // namespace hivecal::streams
