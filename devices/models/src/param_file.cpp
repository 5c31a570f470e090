#include "uhaptics/models/param_file.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

namespace uhaptics {

namespace {

bool isDescriptive(const std::string& member) {
  const auto& d = ParamFile::descriptiveKeys();
  return std::find(d.begin(), d.end(), member) != d.end();
}

bool isUnder(const std::string& key, const std::string& section) {
  return key == section || (key.size() > section.size() && key.compare(0, section.size(), section) == 0 &&
                            key[section.size()] == '/');
}

// Every value path of the file: bare values and documented entries ({"value": ...}) are leaves;
// other objects are sections. Descriptive members are no leaves; any other member of an entry is.
void collectLeaves(const nlohmann::json& node, const std::string& prefix, std::vector<std::string>& out) {
  for (auto it = node.begin(); it != node.end(); ++it) {
    if (isDescriptive(it.key())) continue;
    const std::string key = prefix.empty() ? it.key() : prefix + "/" + it.key();
    const nlohmann::json& child = it.value();
    if (!child.is_object() || child.empty()) {
      out.push_back(key);
    } else if (child.contains("value")) {
      out.push_back(key);
      for (auto m = child.begin(); m != child.end(); ++m)
        if (m.key() != "value" && !isDescriptive(m.key())) out.push_back(key + "/" + m.key());
    } else {
      collectLeaves(child, key, out);
    }
  }
}

// The candidate nearest to key, or "" when none is near enough to be a plausible misspelling.
std::string nearest(const std::string& key, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const auto& c : candidates) {
    const std::size_t d = editDistance(key, c);
    if (d < best_distance) best_distance = d, best = c;
  }
  const std::size_t tolerated = std::max<std::size_t>(2, key.size() / 5);
  return best_distance <= tolerated ? best : std::string();
}

}  // namespace

const std::vector<std::string>& ParamFile::descriptiveKeys() {
  static const std::vector<std::string> keys{"description", "unit", "source", "about", "why"};
  return keys;
}

std::size_t editDistance(const std::string& a, const std::string& b) {
  // Optimal string alignment: a swap of two neighbouring letters counts once.
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[n][m];
}

struct ParamFile::Impl {
  nlohmann::json root;
  std::string origin;

  // What the loaders asked for (the schema as they know it). Loaders take the file by const
  // reference, so the records are mutable; the mutex covers loaders on several threads.
  mutable std::mutex mutex;
  mutable std::vector<ParamField> fields;
  mutable std::set<std::string> asked;  // every key asked for, present or not

  // The node at key, or nullptr. Documented entries {"value": ...} resolve to their value.
  const nlohmann::json* find(const std::string& key) const {
    const nlohmann::json* node = &root;
    std::size_t start = 0;
    while (start <= key.size()) {
      const std::size_t end = key.find('/', start);
      const std::string part = key.substr(start, end == std::string::npos ? std::string::npos : end - start);
      if (!node->is_object()) return nullptr;
      const auto it = node->find(part);
      if (it == node->end()) return nullptr;
      node = &*it;
      if (end == std::string::npos) break;
      start = end + 1;
    }
    if (node->is_object() && node->contains("value")) node = &(*node)["value"];
    return node;
  }

  std::string unitOf(const std::string& key) const {
    const nlohmann::json* node = &root;
    std::size_t start = 0;
    while (true) {
      const std::size_t end = key.find('/', start);
      const std::string part = key.substr(start, end == std::string::npos ? std::string::npos : end - start);
      if (!node->is_object() || !node->contains(part)) return {};
      node = &(*node)[part];
      if (end == std::string::npos) break;
      start = end + 1;
    }
    if (node->is_object() && node->contains("unit") && (*node)["unit"].is_string())
      return (*node)["unit"].get<std::string>();
    return {};
  }

  void record(const std::string& key, ParamField::Kind kind, std::size_t count, double lo, double hi,
              bool required) const {
    std::lock_guard<std::mutex> lock(mutex);
    asked.insert(key);
    for (const auto& f : fields)
      if (f.key == key) return;
    fields.push_back({key, kind, count, lo, hi, required, unitOf(key)});
  }

  void ask(const std::string& key) const {
    std::lock_guard<std::mutex> lock(mutex);
    asked.insert(key);
  }

  std::vector<std::string> leaves() const {
    std::vector<std::string> out;
    collectLeaves(root, "", out);
    return out;
  }

  const nlohmann::json& require(const std::string& key) const {
    const nlohmann::json* node = find(key);
    if (!node) {
      std::string msg = origin + ": missing required field '" + key + "'";
      // A misspelt key is the likeliest cause: name the file's key nearest to the one wanted.
      std::vector<std::string> unasked;
      {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& leaf : leaves())
          if (!asked.count(leaf)) unasked.push_back(leaf);
      }
      const std::string near = nearest(key, unasked);
      if (!near.empty()) msg += " (the file has '" + near + "': misspelt?)";
      throw Error(msg);
    }
    return *node;
  }

  double toNumber(const nlohmann::json& node, const std::string& key) const {
    if (!node.is_number())
      throw Error(origin + ": field '" + key + "' must be a number, found " + node.dump());
    const double v = node.get<double>();
    if (!std::isfinite(v)) throw Error(origin + ": field '" + key + "' is not finite");
    return v;
  }

  void checkRange(double v, const std::string& key, double lo, double hi, const std::string& unit) const {
    if (!(v >= lo && v <= hi)) {
      std::ostringstream msg;
      msg << origin << ": field '" << key << "' = " << v << (unit.empty() ? "" : " " + unit) << " is outside ["
          << lo << ", " << hi << "]";
      throw Error(msg.str());
    }
  }
};

ParamFile::ParamFile(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

ParamFile ParamFile::load(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status))
    throw Error(path + ": is a folder, not a parameter file (give the path of a .json file)");
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw Error(path + ": is not a regular file, not a parameter file");
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open parameter file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw Error(path + ": cannot read parameter file");
  return parse(buffer.str(), path);
}

ParamFile ParamFile::parse(const std::string& text, const std::string& origin) {
  auto impl = std::make_shared<Impl>();
  impl->origin = origin;
  // The keys leading to the value being parsed, so that an error inside the library names the field.
  std::vector<std::string> path;
  const nlohmann::json::parser_callback_t track = [&path](int depth, nlohmann::json::parse_event_t event,
                                                          nlohmann::json& parsed) {
    if (event == nlohmann::json::parse_event_t::key && depth >= 1) {
      path.resize(static_cast<std::size_t>(depth));
      path.back() = parsed.get<std::string>();
    }
    return true;
  };
  try {
    impl->root = nlohmann::json::parse(text, track);
  } catch (const nlohmann::json::exception& e) {
    std::string field;
    for (const auto& part : path) field += (field.empty() ? "" : "/") + part;
    if (field.size() > 6 && field.compare(field.size() - 6, 6, "/value") == 0) field.resize(field.size() - 6);
    // 406: a number beyond a double's range (1e999); the library's own text names no file or field.
    if (e.id == 406)
      throw Error(origin + ": field '" + field + "' is not a finite number (too large for a double)");
    throw Error(origin + ": not valid JSON" + (field.empty() ? "" : " near field '" + field + "'") + " (" +
                e.what() + ")");
  }
  if (!impl->root.is_object()) throw Error(origin + ": the top level must be a JSON object");
  return ParamFile(std::move(impl));
}

const std::string& ParamFile::origin() const noexcept { return impl_->origin; }

void ParamFile::requireFormat(const std::string& device, int supported_version) const {
  const std::string found = text("device");
  if (found != device) fail("field 'device' names '" + found + "', expected '" + device + "'");
  const long version = integer("format_version", 1, 1000000);
  if (version != supported_version)
    fail("format_version " + std::to_string(version) + " is not supported (this build reads version " +
         std::to_string(supported_version) + ")");
}

bool ParamFile::has(const std::string& key) const {
  impl_->ask(key);
  return impl_->find(key) != nullptr;
}

double ParamFile::number(const std::string& key, double lo, double hi) const {
  impl_->record(key, ParamField::Kind::kNumber, 1, lo, hi, true);
  const double v = impl_->toNumber(impl_->require(key), key);
  impl_->checkRange(v, key, lo, hi, impl_->unitOf(key));
  return v;
}

double ParamFile::numberOr(const std::string& key, double fallback, double lo, double hi) const {
  impl_->record(key, ParamField::Kind::kNumber, 1, lo, hi, false);
  if (impl_->find(key) == nullptr) return fallback;
  const double v = impl_->toNumber(*impl_->find(key), key);
  impl_->checkRange(v, key, lo, hi, impl_->unitOf(key));
  return v;
}

long ParamFile::integer(const std::string& key, long lo, long hi) const {
  impl_->record(key, ParamField::Kind::kInteger, 1, static_cast<double>(lo), static_cast<double>(hi), true);
  const nlohmann::json& node = impl_->require(key);
  if (!node.is_number_integer())
    throw Error(impl_->origin + ": field '" + key + "' must be an integer, found " + node.dump());
  // Checked as a double first: an integer beyond long's range must not wrap into the range.
  impl_->checkRange(node.get<double>(), key, static_cast<double>(lo), static_cast<double>(hi), impl_->unitOf(key));
  return node.get<long>();
}

std::vector<double> ParamFile::numbers(const std::string& key, std::size_t n, double lo, double hi) const {
  impl_->record(key, ParamField::Kind::kNumbers, n, lo, hi, true);
  const nlohmann::json& node = impl_->require(key);
  if (!node.is_array() || node.size() != n)
    throw Error(impl_->origin + ": field '" + key + "' must be an array of " + std::to_string(n) +
                " numbers, found " + node.dump());
  const std::string unit = impl_->unitOf(key);
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::string item = key + "[" + std::to_string(i) + "]";
    const double v = impl_->toNumber(node[i], item);
    impl_->checkRange(v, item, lo, hi, unit);
    out.push_back(v);
  }
  return out;
}

std::string ParamFile::text(const std::string& key) const {
  impl_->record(key, ParamField::Kind::kText, 1, 0.0, 0.0, true);
  const nlohmann::json& node = impl_->require(key);
  if (!node.is_string()) throw Error(impl_->origin + ": field '" + key + "' must be a string, found " + node.dump());
  return node.get<std::string>();
}

void ParamFile::rejectUnreadKeys(const std::vector<std::string>& sections_read_elsewhere) const {
  std::vector<std::string> unread, known;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    known.assign(impl_->asked.begin(), impl_->asked.end());
    for (const auto& leaf : impl_->leaves()) {
      if (impl_->asked.count(leaf)) continue;
      // An empty section (e.g. "hand": {}) whose fields the loader asked for is known, merely empty.
      if (std::any_of(impl_->asked.begin(), impl_->asked.end(), [&](const std::string& a) { return isUnder(a, leaf); }))
        continue;
      const bool elsewhere = std::any_of(sections_read_elsewhere.begin(), sections_read_elsewhere.end(),
                                         [&](const std::string& s) { return isUnder(leaf, s); });
      if (!elsewhere) unread.push_back(leaf);
    }
  }
  if (unread.empty()) return;
  std::string msg = impl_->origin + ": unknown key" + (unread.size() > 1 ? "s " : " ");
  for (std::size_t i = 0; i < unread.size(); ++i) {
    msg += (i ? ", '" : "'") + unread[i] + "'";
    const std::string near = nearest(unread[i], known);
    if (!near.empty()) msg += " (did you mean '" + near + "'?)";
  }
  std::string descriptive;
  for (const auto& d : descriptiveKeys()) descriptive += (descriptive.empty() ? "" : ", ") + d;
  msg += "; a parameter file holds only the fields its loader reads (docs/parameter-files.md) and the "
         "descriptive members " + descriptive;
  throw Error(msg);
}

std::vector<ParamField> ParamFile::fields() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->fields;
}

void ParamFile::fail(const std::string& what) const { throw Error(impl_->origin + ": " + what); }

}  // namespace uhaptics
