#pragma once
// The one validation rule of the command-line tools. Every option that takes a number or a path is
// added through a CommandLine, which checks the text before CLI11 converts it and before the tool
// does any work:
//   numbers  finite, inside [min, max], integral where the option is an integer (no "1.5", no "1e3")
//   paths    an input file exists, is a file and is readable; an input folder exists and is a
//            folder; an output folder is a folder or can be created (its nearest existing ancestor is
//            a writable folder); an output file is not a folder and its folder can be created.
// A refused value gets "<option>: <value> is not accepted: <what is>" and exit status 105 (CLI11's
// validation error); an unparsable one CLI11's conversion error (101).
//
// The hidden flag --list-options prints every option of the tool as JSON (its kind, range, count),
// for the generated bad-input suite (tests/tools/bad_input_test.py). An option taking a value that
// was added around this rule is listed with kind "unchecked", which that suite refuses.
#include <CLI/CLI.hpp>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace uhaptics::tools {

class CommandLine {
 public:
  /// tool: the program's name, e.g. "uhaptics-servo" (prefix of the tools' own error messages).
  CommandLine(CLI::App& app, std::string tool);

  static constexpr double kInf = std::numeric_limits<double>::infinity();

  /// A real number in [min, max] (finite even when the bounds are infinite).
  CLI::Option* number(const std::string& name, double& value, const std::string& help, double min, double max);
  /// `count` real numbers (or any count when 0), each in [min, max].
  CLI::Option* numbers(const std::string& name, std::vector<double>& values, int count, const std::string& help,
                       double min, double max);
  /// An integer in [min, max]; the bounds must fit T.
  CLI::Option* integer(const std::string& name, int& value, const std::string& help, long long min, long long max);
  CLI::Option* integer(const std::string& name, unsigned& value, const std::string& help, long long min,
                       long long max);
  CLI::Option* integer(const std::string& name, std::uint64_t& value, const std::string& help, long long min,
                       long long max);
  /// One of `choices` (kind "choice" in --list-options).
  CLI::Option* choice(const std::string& name, std::string& value, const std::string& help,
                      const std::vector<std::string>& choices);
  /// Free text (e.g. key=value metadata): checked by the tool itself (kind "text").
  CLI::Option* text(const std::string& name, std::string& value, const std::string& help);
  CLI::Option* texts(const std::string& name, std::vector<std::string>& values, const std::string& help);

  CLI::Option* inputFile(const std::string& name, std::string& path, const std::string& help);
  CLI::Option* inputFiles(const std::string& name, std::vector<std::string>& paths, const std::string& help);
  CLI::Option* inputFolder(const std::string& name, std::string& path, const std::string& help);
  CLI::Option* outputFile(const std::string& name, std::string& path, const std::string& help);
  CLI::Option* outputFolder(const std::string& name, std::string& path, const std::string& help);

  /// Parses argv. Returns -1 when the tool should go on, else the exit status to return at once
  /// (0 after --help or --list-options; non-zero, with the message on stderr, on a refused value).
  int parse(int argc, char** argv);

  /// Exit statuses shared by the tools (documented in each tool's --help and docs/building.md).
  static constexpr int kAllPass = 0;     // the run completed and no row of its table fails
  static constexpr int kRowsFail = 1;    // the run completed and a row of its table fails
  static constexpr int kRunError = 2;    // the run could not complete (bad file, I/O error, ...)
  static constexpr const char* kExitCodesHelp =
      "Exit status: 0 all checks pass; 1 a check of reproduction.csv fails (FAIL row); 2 the run could not "
      "complete; 101/105 a refused command-line value (conversion/validation).";

 private:
  struct Entry {
    std::string name, kind;  // kind: real, integer, choice, text, input-file, input-folder, output-file, output-folder
    double min = 0.0, max = 0.0;
    int count = 1;  // values per use (0: any)
    std::vector<std::string> choices;
  };
  CLI::Option* record(CLI::Option* option, Entry entry);
  std::string listJson() const;

  CLI::App& app_;
  std::string tool_;
  bool list_options_ = false;
  std::vector<Entry> entries_;
};

}  // namespace uhaptics::tools
