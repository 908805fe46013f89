// MetaImage and NRRD text headers, and the data they promise checked against what the file holds
// before VTK reads it: VTK's readers crash or hang on compressed data that inflates to less (or far
// more) than the header says, and on raw data cut short.
#include "imaging/volume_header.h"

#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fetouch::imaging {

namespace {

std::string trim(std::string t) {
  t.erase(0, t.find_first_not_of(" \t\r"));
  t.erase(t.find_last_not_of(" \t\r") + 1);
  return t;
}

// A header value as quoted in a message: at most 60 characters, control and non-ASCII bytes as '?'.
std::string shown(const std::string& text) {
  std::string out = text.size() <= 60 ? text : text.substr(0, 57) + "...";
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return out;
}

// What a clinical image can be (issue 17): voxels of 1 um to 100 mm, positions within 100 m, at
// most 10^5 voxels along an axis and 2^30 values in all (4 GB as floats).
struct Bounds {
  double low, high;
  const char* what;
};
constexpr Bounds kSpacingMm{1e-3, 100, "a voxel size in mm, 0.001 to 100"};
constexpr Bounds kPositionMm{-1e5, 1e5, "a position in mm, within 100 m"};
constexpr double kMaxValues = double(1u << 30);

// Three numbers (a key absent: nothing to check), each finite and within `bounds`.
void check_vector(const std::filesystem::path& path, const std::string& key, const std::string& value, const Bounds& bounds) {
  if (value.empty()) return;
  std::istringstream in(value);
  int n = 0;
  std::string word;
  for (; in >> word; ++n) {
    char* end = nullptr;
    const double x = std::strtod(word.c_str(), &end);
    if (*end != '\0' || !std::isfinite(x) || x < bounds.low || x > bounds.high || n >= 3)
      throw std::runtime_error(path.string() + ": " + key + " = " + shown(value) + "; expected 3 numbers, each " + bounds.what);
  }
  if (n != 3) throw std::runtime_error(path.string() + ": " + key + " = " + shown(value) + "; expected 3 numbers, each " + bounds.what);
}

// The voxel count of three sizes (DimSize, NRRD sizes), each a whole number from 1 to 10^5 written
// in decimal digits: VTK's NRRD reader takes a size with atoi, so "0x10" or "1e2" would be 0 or 1
// to it (a size of 0 made it copy past its buffer; found by fuzz_volume).
double checked_sizes(const std::filesystem::path& path, const std::string& key, const std::string& value) {
  if (value.empty()) throw std::runtime_error(path.string() + ": the header has no " + key);
  std::istringstream in(value);
  double voxels = 1;
  int n = 0;
  std::string word;
  for (; in >> word; ++n) {
    char* end = nullptr;
    const double d = std::strtod(word.c_str(), &end);
    if (*end != '\0' || word.find_first_not_of("0123456789") != std::string::npos || !(d >= 1 && d <= 1e5) || n >= 3)
      throw std::runtime_error(path.string() + ": " + key + " = " + shown(value) + "; expected 3 whole numbers from 1 to 100000");
    voxels *= d;
  }
  if (n != 3) throw std::runtime_error(path.string() + ": " + key + " = " + shown(value) + "; expected 3 whole numbers from 1 to 100000");
  return voxels;
}

// The size of zlib (or gzip) data once inflated, reading at most `available` bytes from `in`;
// -1 when the stream is cut short or corrupt.
double inflated_size(std::istream& in, double available, bool gzip) {
  z_stream z{};
  if (inflateInit2(&z, gzip ? 16 + MAX_WBITS : MAX_WBITS) != Z_OK) return -1;
  std::vector<char> input(1 << 16), output(1 << 16);
  double total = 0, left = available;
  int status = Z_OK;
  while (status != Z_STREAM_END) {
    if (z.avail_in == 0) {
      if (left <= 0) break;
      in.read(input.data(), static_cast<std::streamsize>(std::min<double>(input.size(), left)));
      const auto got = in.gcount();
      if (got <= 0) break;
      left -= double(got);
      z.next_in = reinterpret_cast<Bytef*>(input.data());
      z.avail_in = static_cast<uInt>(got);
    }
    z.next_out = reinterpret_cast<Bytef*>(output.data());
    z.avail_out = static_cast<uInt>(output.size());
    status = inflate(&z, Z_NO_FLUSH);
    if (status != Z_OK && status != Z_STREAM_END) break;
    total += double(output.size() - z.avail_out);
  }
  inflateEnd(&z);
  return status == Z_STREAM_END ? total : -1;
}

constexpr std::size_t kMaxHeaderBytes = 64u << 20, kMaxHeaderLine = 64u << 10;
// MetaIO reads a key or a value into 500-byte buffers, a key into a 255-byte name and its own
// string fields into 255-byte buffers.
constexpr std::size_t kMaxMetaImageLine = 480, kMaxMetaImageKey = 200, kMaxMetaImageValue = 250;

// MetaImage: VTK's reader fills a short file's missing voxels with whatever it finds, so the data
// size is checked against the header first (uncompressed data; compressed data is checked by zlib).
}  // namespace

// A text header's "key = value" (MetaImage) or "key: value" (NRRD) lines, up to the data: the
// line ElementDataFile (MetaImage) or an empty line (NRRD). `end` is the header's size in bytes.
std::map<std::string, std::string> text_header(const std::filesystem::path& path, char separator,
                                               std::streamoff* end, std::map<std::string, int>* lines) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw std::runtime_error(path.string() + ": not a regular file (a volume is a file, not a FIFO or device)");
  std::ifstream in(path, std::ios::binary);
  std::map<std::string, std::string> keys;
  std::string line;
  std::size_t total = 0;
  // Bounded reads: a file without line breaks (or a huge one) is not a header.
  const auto next_line = [&]() {
    line.clear();
    bool any = false;
    for (int c;;) {
      if ((c = in.get()) == std::char_traits<char>::eof()) {
        // VTK's NRRD reader loops for ever on a header whose last line has no line break.
        if (any)
          throw std::runtime_error(path.string() + ": the header ends without a line break after '" + shown(line) +
                                   "' (cut short?)");
        break;
      }
      any = true;
      if (++total > kMaxHeaderBytes)
        throw std::runtime_error(path.string() + ": a header of over 64 MB; not a MetaImage or NRRD header");
      if (c == '\n') break;
      // A header is text: VTK's NRRD reader loops on control bytes in a field.
      if ((c < 0x20 && c != '\t' && c != '\r') || c >= 0x7f)
        throw std::runtime_error(path.string() + ": byte " + std::to_string(c) +
                                 " in the header; a MetaImage or NRRD header is ASCII text");
      if (line.size() >= kMaxHeaderLine)
        throw std::runtime_error(path.string() + ": a header line of over 64 KB; not a MetaImage or NRRD header");
      line.push_back(static_cast<char>(c));
    }
    return any;
  };
  for (int number = 1; next_line(); ++number) {
    if (end) *end = static_cast<std::streamoff>(total);
    if (separator == ':' && number == 1 &&
        !(trim(line).size() == 8 && trim(line).compare(0, 7, "NRRD000") == 0 && trim(line)[7] >= '1' && trim(line)[7] <= '5'))
      throw std::runtime_error(path.string() + ":1: '" + shown(line) + "' is not a NRRD magic line; expected NRRD0001 to NRRD0005");
    // NRRD's header ends where VTK's reader ends it: at an empty line ("\n\n" or "\n\r\n"). A line of
    // blanks is no end to it (it would read on into the data), so it is refused below.
    if (separator == ':' && (line.empty() || line == "\r")) break;
    if (separator == ':' && !line.empty() && line[0] == '#') continue;  // NRRD comments
    const auto at = line.find(separator);
    // NRRD is strict: after the magic line, each line is "field: value" or "key:=value" (VTK's
    // reader mis-reads "sizes:8 8 8" and crashes on what it made of it).
    if (separator == ':' && number > 1 &&
        (at == std::string::npos || at == 0 || at + 1 >= line.size() || (line[at + 1] != ' ' && line[at + 1] != '=')))
      throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": '" + shown(line) +
                               "' is not a NRRD field; expected 'field: value'");
    // VTK's reader matches a field's name as written: " sizes: 8 8 8" or "sizes : 8 8 8" is no sizes
    // to it (it then read the data through a file it never opened; found by fuzz_volume).
    if (separator == ':' && number > 1 && trim(line.substr(0, at)) != line.substr(0, at))
      throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": '" + shown(line) +
                               "': a NRRD field's name has no blanks around it; expected 'field: value'");
    // MetaImage is strict too: VTK's MetaIO takes a line without '=' as a key whose value is the next
    // line (the data's first bytes, past ElementDataFile) and copies a key of over 254 characters
    // into a 255-byte field name (a fortified abort; found by fuzz_sweep).
    if (separator == '=' && !trim(line).empty()) {
      const auto colon = line.find(':');
      const std::string key = at == std::string::npos ? std::string() : trim(line.substr(0, at));
      if (at == std::string::npos || (colon != std::string::npos && colon < at) || key.empty())
        throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": '" + shown(line) +
                                 "' is not a MetaImage field; expected 'Key = Value'");
      if (key.size() > kMaxMetaImageKey)
        throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": a key of " +
                                 std::to_string(key.size()) + " characters ('" + shown(line) +
                                 "'); MetaImage keys have at most " + std::to_string(kMaxMetaImageKey));
      // MetaIO copies its own string fields (ObjectType, Comment, Name, ...) into 255-byte buffers;
      // only PLUS's per-frame fields (Seq_Frame...), which it keeps as its own strings, may be longer.
      const std::string value = trim(line.substr(at + 1));
      if (value.size() > kMaxMetaImageValue && key.rfind("Seq_Frame", 0) != 0)
        throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": a value of " +
                                 std::to_string(value.size()) + " characters ('" + shown(line) +
                                 "'); MetaImage values have at most " + std::to_string(kMaxMetaImageValue));
      if (line.size() > kMaxMetaImageLine)
        throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": a header line of " +
                                 std::to_string(line.size()) + " characters; MetaImage reads at most " +
                                 std::to_string(kMaxMetaImageLine));
    }
    if (at == std::string::npos) continue;
    // NRRD's "key:=value" pairs are not fields: kept apart, so that "sizes:=8 8 8" does not pass for
    // the sizes field VTK's reader then lacks (it crashed reading the data; found by fuzz_volume).
    const bool pair = separator == ':' && line.compare(at, 2, ":=") == 0;
    const std::string key = (pair ? "key-value pair " : "") + trim(line.substr(0, at)), value = trim(line.substr(at + 1 + pair));
    // A field given twice: this parser and VTK's could each believe a different one.
    if (!keys.emplace(key, value).second)
      throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": '" + shown(key) +
                               "' is given a second time; a header names each field once");
    if (lines) (*lines)[key] = number;
    if (key == "ElementDataFile") break;  // MetaImage's last header line
  }
  return keys;
}

void check_metaimage_size(const std::filesystem::path& path) {
  std::streamoff header = 0;
  std::map<std::string, std::string> keys = text_header(path, '=', &header);
  const auto get = [&](const std::string& key) { return keys.count(key) ? keys[key] : std::string(); };
  const std::string ndims = get("NDims");
  if (!ndims.empty() && ndims != "3")
    throw std::runtime_error(path.string() + ": NDims = " + shown(ndims) + "; a volume has 3 dimensions");
  const double voxels = checked_sizes(path, "DimSize", get("DimSize"));
  check_vector(path, "ElementSpacing", get("ElementSpacing"), kSpacingMm);
  check_vector(path, "ElementSize", get("ElementSize"), kSpacingMm);
  for (const char* key : {"Offset", "Origin", "Position"}) check_vector(path, key, get(key), kPositionMm);
  static const std::map<std::string, int> bytes{{"MET_UCHAR", 1}, {"MET_CHAR", 1},   {"MET_USHORT", 2}, {"MET_SHORT", 2},
                                                {"MET_UINT", 4},  {"MET_INT", 4},    {"MET_FLOAT", 4},  {"MET_DOUBLE", 8},
                                                {"MET_ULONG", 8}, {"MET_LONG", 8}};
  const auto type = bytes.find(get("ElementType"));
  if (type == bytes.end()) throw std::runtime_error(path.string() + ": unknown ElementType '" + get("ElementType") + "'");
  const std::string channels = get("ElementNumberOfChannels");
  double channel_count = 1;
  if (!channels.empty()) {
    std::istringstream in(channels);
    std::string rest;
    if (!(in >> channel_count) || (in >> rest) || channel_count != std::floor(channel_count) || channel_count < 1 ||
        channel_count > 16)
      throw std::runtime_error(path.string() + ": ElementNumberOfChannels = " + shown(channels) + "; expected 1 to 16");
  }
  if (voxels * channel_count > kMaxValues)
    throw std::runtime_error(path.string() + ": " + shown(get("DimSize")) + " voxels of " + shown(channels.empty() ? "1" : channels) +
                             " channels; at most 2^30 values fit the memory budget (4 GB as floats)");
  const double expected = voxels * type->second * channel_count;
  const std::string data = get("ElementDataFile");
  double available = 0;
  if (data == "LOCAL") {
    available = double(std::filesystem::file_size(path)) - double(header);
  } else {
    const auto file = path.parent_path() / data;
    std::error_code error;
    if (!std::filesystem::exists(file, error))
      throw std::runtime_error(path.string() + ": its data file " + file.string() + " is missing");
    if (!std::filesystem::is_regular_file(file, error))
      throw std::runtime_error(path.string() + ": its data file " + file.string() + " is not a regular file (a FIFO, device or folder)");
    available = double(std::filesystem::file_size(file));
  }
  const std::string compressed = get("CompressedData");
  if (compressed == "True" || compressed == "true") {
    // Compressed: inflated, the data must give exactly what the header says (VTK's reader would
    // leave the voxels of a cut-short stream as it found them).
    std::ifstream data_in(data == "LOCAL" ? path : path.parent_path() / data, std::ios::binary);
    if (data == "LOCAL") data_in.seekg(header);
    const double inflated = inflated_size(data_in, available, false);
    if (inflated < 0)
      throw std::runtime_error(path.string() + ": its compressed data is cut short or corrupt (zlib could not inflate it)");
    available = inflated;
  }
  if (available < expected)
    throw std::runtime_error(path.string() + ": DimSize " + get("DimSize") + " of " + get("ElementType") + " needs " +
                             std::to_string(static_cast<long long>(expected)) + " bytes but the file holds " +
                             std::to_string(static_cast<long long>(available)));
}

// NRRD: the same check for raw and gzip-encoded data, inline or in a detached file.
void check_nrrd_size(const std::filesystem::path& path) {
  std::streamoff header = 0;
  std::map<std::string, int> line_of;
  auto keys = text_header(path, ':', &header, &line_of);
  static const std::map<std::string, int> bytes{
      {"uchar", 1},  {"unsigned char", 1}, {"uint8", 1},  {"uint8_t", 1},  {"signed char", 1}, {"int8", 1},
      {"char", 1},   {"short", 2},         {"ushort", 2}, {"unsigned short", 2}, {"int16", 2}, {"uint16", 2},
      {"int", 4},    {"uint", 4},          {"unsigned int", 4}, {"int32", 4}, {"uint32", 4}, {"float", 4},
      {"double", 8}, {"longlong", 8},      {"int64", 8},  {"uint64", 8}};
  const auto type = bytes.find(keys["type"]);
  if (type == bytes.end()) throw std::runtime_error(path.string() + ": unknown NRRD type '" + keys["type"] + "'");
  // The fields NRRD requires (VTK's reader goes on without them, then crashes reading the data).
  for (const char* field : {"type", "dimension", "sizes", "encoding"})
    if (!keys.count(field)) throw std::runtime_error(path.string() + ": no '" + field + ":' field (NRRD requires type, dimension, sizes and encoding)");
  if (keys["dimension"] != "3")
    throw std::runtime_error(path.string() + ": dimension: " + shown(keys["dimension"]) + "; a volume has 3 dimensions");
  // VTK's reader gives "sizes" and "spacings" as many axes as it knows of when it meets them: none
  // before "dimension" (NRRD puts dimension before every per-axis field), and "space dimension"
  // changes the count. Axes it lacks leave it reading the data through a file it never opened
  // (a crash; found by fuzz_volume).
  for (const char* field : {"sizes", "spacings", "thicknesses", "axis mins", "axismins", "axis maxs", "axismaxs", "centers",
                            "centerings", "labels", "units", "kinds", "space directions"})
    if (keys.count(field) && line_of[field] < line_of["dimension"])
      throw std::runtime_error(path.string() + ":" + std::to_string(line_of[field]) + ": '" + field +
                               "' comes before 'dimension'; NRRD gives the dimension before any per-axis field");
  if (keys.count("space dimension") && keys["space dimension"] != "3")
    throw std::runtime_error(path.string() + ":" + std::to_string(line_of["space dimension"]) + ": space dimension: " +
                             shown(keys["space dimension"]) + "; a volume's space has 3 dimensions");
  const double voxels = checked_sizes(path, "sizes", keys["sizes"]);
  // VTK's reader takes a first axis of 9 samples or fewer for the components of a vector (an RGB
  // axis), so 8 x 12 x 8 voxels would come back as 12 x 8 x 1 vectors of 8.
  if (const int first = std::atoi(keys["sizes"].c_str()); first <= 9)
    throw std::runtime_error(path.string() + ":" + std::to_string(line_of["sizes"]) + ": sizes: " + shown(keys["sizes"]) +
                             "; a first axis of " + std::to_string(first) +
                             " samples is read as a vector's components, not as space (at least 10 along the first axis; or use .mha)");
  if (voxels > kMaxValues)
    throw std::runtime_error(path.string() + ": sizes " + shown(keys["sizes"]) + "; at most 2^30 voxels fit the memory budget");
  check_vector(path, "spacings", keys["spacings"], kSpacingMm);
  // "space directions: (x,y,z) (x,y,z) (x,y,z)" and "space origin: (x,y,z)", parsed strictly here
  // (VTK's reader does not stop on a malformed one).
  for (const auto& [key, vectors] : {std::pair<const char*, int>{"space directions", 3}, {"space origin", 1}}) {
    if (!keys.count(key)) continue;
    std::string text = keys[key];
    int found = 0;
    for (std::size_t at = 0; (at = text.find_first_not_of(" \t", at)) != std::string::npos; ++found) {
      if (text.compare(at, 4, "none") == 0 && vectors == 3) {
        at += 4;
        continue;
      }
      const std::size_t close = text.find(')', at);
      double a, b, c;
      char tail;
      if (text[at] != '(' || close == std::string::npos ||
          std::sscanf(text.substr(at + 1, close - at - 1).c_str(), " %lf , %lf , %lf %c", &a, &b, &c, &tail) != 3 ||
          !std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c))
        throw std::runtime_error(path.string() + ": " + key + ": " + shown(text) + "; expected " + std::to_string(vectors) +
                                 " vector(s) (x,y,z) of finite numbers");
      at = close + 1;
    }
    if (found != vectors)
      throw std::runtime_error(path.string() + ": " + key + ": " + shown(text) + "; expected " + std::to_string(vectors) + " vector(s) (x,y,z)");
  }
  const double expected = type->second * voxels;
  const std::string encoding = keys["encoding"];
  const std::string detached = keys.count("data file") ? keys["data file"] : keys["datafile"];
  const std::filesystem::path file = detached.empty() ? path : path.parent_path() / detached;
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error))
    throw std::runtime_error(path.string() + ": its data file " + file.string() + " is missing or not a regular file");
  double available = double(std::filesystem::file_size(file)) - (detached.empty() ? double(header) : 0);
  if (encoding == "gzip" || encoding == "gz") {
    std::ifstream in(file, std::ios::binary);
    if (detached.empty()) in.seekg(header);
    available = inflated_size(in, available, true);
    if (available < 0) throw std::runtime_error(path.string() + ": its gzip data is cut short or corrupt");
  } else if (encoding == "ascii" || encoding == "text" || encoding == "txt") {
    return;  // text encodings: VTK's reader checks as it parses
  } else if (encoding != "raw") {
    throw std::runtime_error(path.string() + ": encoding: " + shown(encoding) + "; expected raw, gzip or ascii");
  }
  if (available < expected)
    throw std::runtime_error(path.string() + ": sizes " + keys["sizes"] + " of " + keys["type"] + " need " +
                             std::to_string(static_cast<long long>(expected)) + " bytes but the data holds " +
                             std::to_string(static_cast<long long>(available)));
}

}  // namespace fetouch::imaging
