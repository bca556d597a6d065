// Human-readable and JSON forms of the encoder's per-chunk size report.
#ifndef ECRF_TOOLS_ENCODE_REPORT_H_
#define ECRF_TOOLS_ENCODE_REPORT_H_

#include <cstdio>
#include <nlohmann/json.hpp>

#include "encoder/scene_encoder.h"

namespace ecrf {
namespace tools {

void PrintEncodeReport(FILE* out, const encoder::EncodeReport& report);
nlohmann::json EncodeReportJson(const encoder::EncodeReport& report);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_ENCODE_REPORT_H_
