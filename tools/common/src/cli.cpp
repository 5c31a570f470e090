#include "uhaptics/tools/cli.hpp"

#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace uhaptics::tools {

namespace {

std::string shortNumber(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

std::string refused(const std::string& value, const std::string& accepted) {
  return quoted(value) + " is not accepted: " + accepted;
}

std::string realRange(double min, double max) {
  return "a finite number in [" + shortNumber(min) + ", " + shortNumber(max) + "]";
}

std::string integerRange(long long min, long long max) {
  return "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
}

// Empty when `text` is a finite number in [min, max], else why not.
std::string checkReal(const std::string& text, double min, double max) {
  const std::string accepted = realRange(min, max);
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return refused(text, accepted);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(v) || errno == ERANGE || v < min || v > max)
    return refused(text, accepted);
  return {};
}

std::string checkInteger(const std::string& text, long long min, long long max) {
  const std::string accepted = integerRange(min, max);
  if (text.empty() || !(std::isdigit(static_cast<unsigned char>(text.front())) || text.front() == '-' ||
                        text.front() == '+'))
    return refused(text, accepted);
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (end != text.c_str() + text.size() || errno == ERANGE || v < min || v > max) return refused(text, accepted);
  return {};
}

bool writable(const fs::path& p) { return ::access(p.c_str(), W_OK) == 0; }
bool readable(const fs::path& p) { return ::access(p.c_str(), R_OK) == 0; }

// Empty when `folder` is a writable folder or can be created; else why not.
std::string checkCreatableFolder(const fs::path& folder) {
  std::error_code ec;
  fs::path p = folder.empty() ? fs::path(".") : folder;
  if (fs::exists(p, ec)) {
    if (!fs::is_directory(p, ec)) return "a folder is expected, " + p.string() + " is a file";
    if (!writable(p)) return "folder " + p.string() + " is not writable";
    return {};
  }
  // The nearest ancestor that exists must be a writable folder for the folder to be created.
  fs::path ancestor = p;
  do {
    ancestor = ancestor.has_parent_path() && ancestor.parent_path() != ancestor ? ancestor.parent_path() : fs::path(".");
  } while (!fs::exists(ancestor, ec) && ancestor != fs::path("."));
  if (!fs::is_directory(ancestor, ec)) return "cannot be created: " + ancestor.string() + " is not a folder";
  if (!writable(ancestor)) return "cannot be created: " + ancestor.string() + " is not writable";
  return {};
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string jsonNumber(double v) { return std::isfinite(v) ? shortNumber(v) : "null"; }

}  // namespace

CommandLine::CommandLine(CLI::App& app, std::string tool) : app_(app), tool_(std::move(tool)) {
  app_.add_flag("--list-options", list_options_, "print the options and their accepted values as JSON")
      ->group("");  // hidden: for the bad-input suite
}

CLI::Option* CommandLine::record(CLI::Option* option, Entry entry) {
  entry.name = option->get_name();
  entries_.push_back(std::move(entry));
  return option;
}

CLI::Option* CommandLine::number(const std::string& name, double& value, const std::string& help, double min,
                                 double max) {
  CLI::Option* o = app_.add_option(name, value, help + " (" + realRange(min, max) + ")");
  o->check(CLI::Validator([min, max](std::string& s) { return checkReal(s, min, max); }, "", "real"));
  return record(o, {"", "real", min, max, 1, {}});
}

CLI::Option* CommandLine::numbers(const std::string& name, std::vector<double>& values, int count,
                                  const std::string& help, double min, double max) {
  CLI::Option* o = app_.add_option(name, values, help + " (each " + realRange(min, max) + ")");
  if (count > 0) o->expected(count);
  o->check(CLI::Validator([min, max](std::string& s) { return checkReal(s, min, max); }, "", "real"));
  return record(o, {"", "real", min, max, count, {}});
}

namespace {
template <typename T>
CLI::Option* addInteger(CLI::App& app, const std::string& name, T& value, const std::string& help, long long min,
                        long long max) {
  if (min < static_cast<long long>(std::numeric_limits<T>::min()) ||
      static_cast<unsigned long long>(max) > static_cast<unsigned long long>(std::numeric_limits<T>::max()))
    throw std::logic_error(name + ": range does not fit the option's type");
  CLI::Option* o = app.add_option(name, value, help + " (" + integerRange(min, max) + ")");
  o->check(CLI::Validator([min, max](std::string& s) { return checkInteger(s, min, max); }, "", "integer"));
  return o;
}
}  // namespace

CLI::Option* CommandLine::integer(const std::string& name, int& value, const std::string& help, long long min,
                                  long long max) {
  return record(addInteger(app_, name, value, help, min, max),
                {"", "integer", static_cast<double>(min), static_cast<double>(max), 1, {}});
}
CLI::Option* CommandLine::integer(const std::string& name, unsigned& value, const std::string& help, long long min,
                                  long long max) {
  return record(addInteger(app_, name, value, help, min, max),
                {"", "integer", static_cast<double>(min), static_cast<double>(max), 1, {}});
}
CLI::Option* CommandLine::integer(const std::string& name, std::uint64_t& value, const std::string& help,
                                  long long min, long long max) {
  return record(addInteger(app_, name, value, help, min, max),
                {"", "integer", static_cast<double>(min), static_cast<double>(max), 1, {}});
}

CLI::Option* CommandLine::choice(const std::string& name, std::string& value, const std::string& help,
                                 const std::vector<std::string>& choices) {
  CLI::Option* o = app_.add_option(name, value, help);
  o->check(CLI::IsMember(choices));
  return record(o, {"", "choice", 0, 0, 1, choices});
}

CLI::Option* CommandLine::text(const std::string& name, std::string& value, const std::string& help) {
  return record(app_.add_option(name, value, help), {"", "text", 0, 0, 1, {}});
}

CLI::Option* CommandLine::texts(const std::string& name, std::vector<std::string>& values, const std::string& help) {
  return record(app_.add_option(name, values, help), {"", "text", 0, 0, 0, {}});
}

namespace {
std::string checkInputFile(const std::string& s) {
  std::error_code ec;
  if (s.empty()) return refused(s, "the path of an existing file");
  if (!fs::exists(s, ec)) return refused(s, "an existing file (it does not exist)");
  if (fs::is_directory(s, ec)) return refused(s, "a file (it is a folder)");
  if (!readable(s)) return refused(s, "a readable file");
  return {};
}
}  // namespace

CLI::Option* CommandLine::inputFile(const std::string& name, std::string& path, const std::string& help) {
  CLI::Option* o = app_.add_option(name, path, help);
  o->check(CLI::Validator([](std::string& s) { return checkInputFile(s); }, "", "file"));
  return record(o, {"", "input-file", 0, 0, 1, {}});
}

CLI::Option* CommandLine::inputFiles(const std::string& name, std::vector<std::string>& paths,
                                     const std::string& help) {
  CLI::Option* o = app_.add_option(name, paths, help);
  o->check(CLI::Validator([](std::string& s) { return checkInputFile(s); }, "", "file"));
  return record(o, {"", "input-file", 0, 0, 0, {}});
}

CLI::Option* CommandLine::inputFolder(const std::string& name, std::string& path, const std::string& help) {
  CLI::Option* o = app_.add_option(name, path, help);
  o->check(CLI::Validator(
      [](std::string& s) -> std::string {
        std::error_code ec;
        if (s.empty()) return refused(s, "the path of an existing folder");
        if (!fs::exists(s, ec)) return refused(s, "an existing folder (it does not exist)");
        if (!fs::is_directory(s, ec)) return refused(s, "a folder (it is a file)");
        if (!readable(s)) return refused(s, "a readable folder");
        return {};
      },
      "", "folder"));
  return record(o, {"", "input-folder", 0, 0, 1, {}});
}

CLI::Option* CommandLine::outputFile(const std::string& name, std::string& path, const std::string& help) {
  CLI::Option* o = app_.add_option(name, path, help);
  o->check(CLI::Validator(
      [](std::string& s) -> std::string {
        std::error_code ec;
        if (s.empty()) return refused(s, "the path of a file to write");
        if (fs::is_directory(s, ec)) return refused(s, "a file to write (it is a folder)");
        if (fs::exists(s, ec) && !writable(s)) return refused(s, "a writable file");
        const std::string why = checkCreatableFolder(fs::path(s).parent_path());
        return why.empty() ? why : refused(s, "a file whose folder can be written (" + why + ")");
      },
      "", "file"));
  return record(o, {"", "output-file", 0, 0, 1, {}});
}

CLI::Option* CommandLine::outputFolder(const std::string& name, std::string& path, const std::string& help) {
  CLI::Option* o = app_.add_option(name, path, help);
  o->check(CLI::Validator(
      [](std::string& s) -> std::string {
        if (s.empty()) return refused(s, "the path of a folder to write into");
        const std::string why = checkCreatableFolder(s);
        return why.empty() ? why : refused(s, "a writable folder (" + why + ")");
      },
      "", "folder"));
  return record(o, {"", "output-folder", 0, 0, 1, {}});
}

std::string CommandLine::listJson() const {
  std::ostringstream os;
  os << "{\"tool\": " << jsonString(tool_) << ", \"options\": [\n";
  bool first = true;
  auto begin = [&] {
    os << (first ? "  " : ",\n  ");
    first = false;
  };
  for (const Entry& e : entries_) {
    begin();
    os << "{\"name\": " << jsonString(e.name) << ", \"kind\": " << jsonString(e.kind) << ", \"count\": " << e.count;
    if (e.kind == "real" || e.kind == "integer")
      os << ", \"min\": " << jsonNumber(e.min) << ", \"max\": " << jsonNumber(e.max);
    if (!e.choices.empty()) {
      os << ", \"choices\": [";
      for (std::size_t i = 0; i < e.choices.size(); ++i) os << (i ? ", " : "") << jsonString(e.choices[i]);
      os << "]";
    }
    os << "}";
  }
  // Options taking a value that were added around this rule: the suite refuses them.
  for (const CLI::Option* o : app_.get_options()) {
    if (o->get_expected_max() == 0 || o->get_name().empty()) continue;  // flags, the hidden --list-options
    bool known = false;
    for (const Entry& e : entries_) known = known || e.name == o->get_name();
    if (known) continue;
    begin();
    os << "{\"name\": " << jsonString(o->get_name()) << ", \"kind\": \"unchecked\"}";
  }
  os << "\n]}\n";
  return os.str();
}

int CommandLine::parse(int argc, char** argv) {
  try {
    app_.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (!list_options_ || e.get_exit_code() != 0) {
      if (e.get_exit_code() != 0) std::cerr << tool_ << ": ";
      return app_.exit(e);
    }
  }
  if (list_options_) {
    std::cout << listJson();
    return 0;
  }
  return -1;
}

}  // namespace uhaptics::tools
