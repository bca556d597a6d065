#include "trainer/data/npy.h"

#include <cctype>
#include <cstring>
#include <stdexcept>

#include "trainer/data/file_io.h"

namespace ecrf::trainer {
namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr size_t kMagicSize = 6;

[[noreturn]] void Fail(const std::string& name, const std::string& problem) {
  throw std::runtime_error(name + ": " + problem);
}

// The value of 'key' in the header's Python dict literal, as its raw text (up to the next
// top-level comma or closing brace).
std::string DictValue(const std::string& name, const std::string& header, const std::string& key) {
  size_t at = std::string::npos;
  for (const char quote : {'\'', '"'}) {
    const std::string quoted = std::string(1, quote) + key + quote;
    at = header.find(quoted);
    if (at != std::string::npos) {
      at += quoted.size();
      break;
    }
  }
  if (at == std::string::npos) Fail(name, "malformed .npy header: no '" + key + "' in " + header);
  at = header.find(':', at);
  if (at == std::string::npos) Fail(name, "malformed .npy header: no ':' after '" + key + "'");
  ++at;
  int depth = 0;
  size_t end = at;
  for (; end < header.size(); ++end) {
    const char c = header[end];
    if (c == '(' || c == '[') ++depth;
    if (c == ')' || c == ']') --depth;
    if (depth == 0 && (c == ',' || c == '}')) break;
    if (depth < 0) break;
  }
  std::string value = header.substr(at, end - at);
  const size_t first = value.find_first_not_of(" \t");
  const size_t last = value.find_last_not_of(" \t");
  return first == std::string::npos ? std::string() : value.substr(first, last - first + 1);
}

}  // namespace

NpyMatrix ParseNpyMatrix(const std::string& name, const std::vector<uint8_t>& bytes) {
  if (bytes.size() < 10 || std::memcmp(bytes.data(), kMagic, kMagicSize) != 0) {
    Fail(name, "not a .npy file (no \\x93NUMPY magic)");
  }
  const int major = bytes[6];
  size_t header_size = 0, header_start = 0;
  if (major == 1) {
    header_size = bytes[8] | size_t(bytes[9]) << 8;
    header_start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) Fail(name, ".npy file truncated in its header");
    header_size =
        bytes[8] | size_t(bytes[9]) << 8 | size_t(bytes[10]) << 16 | size_t(bytes[11]) << 24;
    header_start = 12;
  } else {
    Fail(name, ".npy format version " + std::to_string(major) + " is not supported (1, 2 or 3)");
  }
  if (header_start + header_size > bytes.size()) Fail(name, ".npy file truncated in its header");
  const std::string header(bytes.begin() + header_start,
                           bytes.begin() + header_start + header_size);

  std::string descr = DictValue(name, header, "descr");
  if (descr.size() >= 2 && (descr.front() == '\'' || descr.front() == '"'))
    descr = descr.substr(1, descr.size() - 2);
  size_t item = 0;
  if (descr == "<f8") {
    item = 8;
  } else if (descr == "<f4") {
    item = 4;
  } else {
    Fail(name, "dtype '" + descr +
                   "' is not supported (need little-endian float64 '<f8' or float32 '<f4')");
  }
  if (DictValue(name, header, "fortran_order") != "False")
    Fail(name, "Fortran-order arrays are not supported");

  const std::string shape = DictValue(name, header, "shape");
  std::vector<int64_t> dims;
  if (shape.size() < 2 || shape.front() != '(' || shape.back() != ')')
    Fail(name, "malformed .npy shape " + shape);
  for (size_t i = 1; i + 1 < shape.size();) {
    if (std::isdigit(static_cast<unsigned char>(shape[i]))) {
      int64_t v = 0;
      while (i + 1 < shape.size() && std::isdigit(static_cast<unsigned char>(shape[i]))) {
        v = v * 10 + (shape[i++] - '0');
        if (v > (int64_t(1) << 40)) Fail(name, "implausible .npy shape " + shape);
      }
      dims.push_back(v);
    } else if (shape[i] == ',' || shape[i] == ' ' || shape[i] == 'L') {
      ++i;
    } else {
      Fail(name, "malformed .npy shape " + shape);
    }
  }
  if (dims.size() != 2) Fail(name, "array has shape " + shape + "; need a 2-D array");

  NpyMatrix m;
  m.rows = dims[0];
  m.cols = dims[1];
  const size_t count = size_t(m.rows * m.cols);
  const size_t data_start = header_start + header_size;
  if (bytes.size() - data_start < count * item) {
    Fail(name, ".npy data truncated: shape " + shape + " needs " + std::to_string(count * item) +
                   " bytes, the file has " + std::to_string(bytes.size() - data_start));
  }
  m.values.resize(count);
  const uint8_t* p = bytes.data() + data_start;
  for (size_t i = 0; i < count; ++i, p += item) {
    // Assemble little-endian bytes so the result does not depend on the host's byte order.
    uint64_t bits = 0;
    for (size_t b = 0; b < item; ++b) bits |= uint64_t(p[b]) << (8 * b);
    if (item == 8) {
      std::memcpy(&m.values[i], &bits, 8);
    } else {
      const uint32_t narrow = uint32_t(bits);
      float f;
      std::memcpy(&f, &narrow, 4);
      m.values[i] = f;
    }
  }
  return m;
}

NpyMatrix ReadNpyMatrix(const std::string& path) {
  return ParseNpyMatrix(path, ReadWholeFile(path));  // regular files only
}

}  // namespace ecrf::trainer
