#include "uhaptics/models/param_file.hpp"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace uhaptics {

struct ParamFile::Impl {
  nlohmann::json root;
  std::string origin;

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
      return " " + (*node)["unit"].get<std::string>();
    return {};
  }

  const nlohmann::json& require(const std::string& key) const {
    const nlohmann::json* node = find(key);
    if (!node) throw Error(origin + ": missing required field '" + key + "'");
    return *node;
  }

  double toNumber(const nlohmann::json& node, const std::string& key) const {
    if (!node.is_number())
      throw Error(origin + ": field '" + key + "' must be a number, found " + node.dump());
    const double v = node.get<double>();
    if (!std::isfinite(v)) throw Error(origin + ": field '" + key + "' is not finite");
    return v;
  }

  void checkRange(double v, const std::string& key, double lo, double hi) const {
    if (v < lo || v > hi) {
      std::ostringstream msg;
      msg << origin << ": field '" << key << "' = " << v << unitOf(key) << " is outside [" << lo << ", "
          << hi << "]";
      throw Error(msg.str());
    }
  }
};

ParamFile::ParamFile(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

ParamFile ParamFile::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open parameter file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse(buffer.str(), path);
}

ParamFile ParamFile::parse(const std::string& text, const std::string& origin) {
  auto impl = std::make_shared<Impl>();
  impl->origin = origin;
  try {
    impl->root = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(origin + ": not valid JSON (" + e.what() + ")");
  }
  if (!impl->root.is_object()) throw Error(origin + ": the top level must be a JSON object");
  return ParamFile(std::move(impl));
}

const std::string& ParamFile::origin() const noexcept { return impl_->origin; }

void ParamFile::requireFormat(const std::string& device, int supported_version) const {
  const std::string found = text("device");
  if (found != device) fail("describes device '" + found + "', expected '" + device + "'");
  const long version = integer("format_version", 1, 1000000);
  if (version != supported_version)
    fail("format_version " + std::to_string(version) + " is not supported (this build reads version " +
         std::to_string(supported_version) + ")");
}

bool ParamFile::has(const std::string& key) const { return impl_->find(key) != nullptr; }

double ParamFile::number(const std::string& key, double lo, double hi) const {
  const double v = impl_->toNumber(impl_->require(key), key);
  impl_->checkRange(v, key, lo, hi);
  return v;
}

double ParamFile::numberOr(const std::string& key, double fallback, double lo, double hi) const {
  return has(key) ? number(key, lo, hi) : fallback;
}

long ParamFile::integer(const std::string& key, long lo, long hi) const {
  const nlohmann::json& node = impl_->require(key);
  if (!node.is_number_integer())
    throw Error(impl_->origin + ": field '" + key + "' must be an integer, found " + node.dump());
  const long v = node.get<long>();
  impl_->checkRange(static_cast<double>(v), key, static_cast<double>(lo), static_cast<double>(hi));
  return v;
}

std::vector<double> ParamFile::numbers(const std::string& key, std::size_t n, double lo, double hi) const {
  const nlohmann::json& node = impl_->require(key);
  if (!node.is_array() || node.size() != n)
    throw Error(impl_->origin + ": field '" + key + "' must be an array of " + std::to_string(n) +
                " numbers, found " + node.dump());
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::string item = key + "[" + std::to_string(i) + "]";
    const double v = impl_->toNumber(node[i], item);
    impl_->checkRange(v, item, lo, hi);
    out.push_back(v);
  }
  return out;
}

std::string ParamFile::text(const std::string& key) const {
  const nlohmann::json& node = impl_->require(key);
  if (!node.is_string()) throw Error(impl_->origin + ": field '" + key + "' must be a string, found " + node.dump());
  return node.get<std::string>();
}

void ParamFile::fail(const std::string& what) const { throw Error(impl_->origin + ": " + what); }

}  // namespace uhaptics
