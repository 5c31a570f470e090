// The libusb transport without hardware: the real libusb runs discovery in this environment and
// must say clearly that the device is absent; the advice for the other opening errors is checked
// as text; descriptors load from a parameter file's "usb" section; the udev rules CMake generates
// from the parameter files agree with them as the host reads them.
#include <catch2/catch.hpp>

#include <libusb.h>

#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "params.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/protocol/libusb_transport.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/param_file.hpp"

using namespace uhaptics;

namespace {

DeviceDescriptor tauDescriptor() {
  DeviceDescriptor d;
  d.name = "TAU";
  d.type = wire::DeviceType{2};
  d.vendor_id = 0x1209;
  d.product_id = 0x0002;
  d.joints = 6;
  d.actuators = 6;
  d.effort_limit.fill(2.0);
  return d;
}

const std::string kUdevRules = UHAPTICS_UDEV_RULES;

}  // namespace

TEST_CASE("no device: the real libusb path says so and lists what it found", "[usb][libusb]") {
  // No uhaptics board is attached to a CI machine (and its USB bus may not be visible at all).
  try {
    LibusbTransport transport(tauDescriptor());
    FAIL("a TAU board (1209:0002) is attached: this test expects none");
  } catch (const Error& e) {
    const std::string m = e.what();
    INFO(m);
    const bool absent = m.find("no USB device 1209:0002 (TAU) found. USB devices present:") != std::string::npos;
    const bool no_bus = m.find("libusb_init failed") != std::string::npos;
    CHECK((absent || no_bus));
    if (absent) {
      CHECK(m.find("usb/vendor_id and usb/product_id") != std::string::npos);
      // Either the list of devices present or the hint that the bus is not visible.
      const auto found = LibusbTransport::listDevices();
      if (found.empty()) CHECK(m.find("/dev/bus/usb") != std::string::npos);
      for (const auto& line : found) CHECK(m.find(line) != std::string::npos);
    }
  }
}

TEST_CASE("opening errors come with what to do", "[usb][libusb]") {
  const DeviceDescriptor d = tauDescriptor();
  const std::string access = libusbOpenAdvice(LIBUSB_ERROR_ACCESS, d);
  CHECK(access.find("permission denied") != std::string::npos);
  CHECK(access.find("share/uhaptics/udev/99-uhaptics.rules") != std::string::npos);
  CHECK(access.find("udevadm") != std::string::npos);
  const std::string busy = libusbOpenAdvice(LIBUSB_ERROR_BUSY, d);
  CHECK(busy.find("interface 0 of TAU (USB 1209:0002) is busy") != std::string::npos);
  CHECK(libusbOpenAdvice(LIBUSB_ERROR_NOT_FOUND, d).find("usb/interface") != std::string::npos);
  CHECK(libusbOpenAdvice(LIBUSB_ERROR_IO, d).find("Input/Output") != std::string::npos);
}

TEST_CASE("the generated udev rules are the registered devices' USB ids, one rule each", "[usb][udev]") {
  // Rules and the comment line above each.
  std::istringstream text(test::readFile(kUdevRules));
  std::vector<std::string> rules;
  std::map<std::string, std::string> comment_of;
  std::string line, comment;
  while (std::getline(text, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      comment = line;
      continue;
    }
    rules.push_back(line);
    comment_of[line] = comment;
  }
  REQUIRE_FALSE(rules.empty());
  // The ids as the host reads them from each registered device's parameter file.
  std::set<std::string> expected;
  for (const DeviceDefinition* device : deviceDefinitions()) {
    const DeviceDescriptor d = boardSpec(*device, UHAPTICS_PARAMS_DIR).descriptor;
    char rule[160];
    std::snprintf(rule, sizeof rule,
                  "SUBSYSTEM==\"usb\", ATTRS{idVendor}==\"%04x\", ATTRS{idProduct}==\"%04x\", MODE=\"0660\", "
                  "GROUP=\"plugdev\", TAG+=\"uaccess\"",
                  d.vendor_id, d.product_id);
    INFO(device->name << ": " << rule);
    expected.insert(rule);
    REQUIRE(comment_of.count(rule) == 1);
    const std::string& above = comment_of[rule];  // "# <name>: devices/<folder>/params/<file>"
    CHECK(above.rfind("# " + device->name + ": devices/", 0) == 0);
    const std::string file = "/params/" + device->params_file;
    CHECK((above.size() > file.size() && above.compare(above.size() - file.size(), file.size(), file) == 0));
  }
  CHECK(rules.size() == expected.size());  // no rule twice, none for anything else
  CHECK(std::set<std::string>(rules.begin(), rules.end()) == expected);
}

TEST_CASE("descriptor from a parameter file's usb section", "[usb][params]") {
  const char* text = R"({"device": "tau", "format_version": 1,
    "usb": {"vendor_id": {"value": 4617, "source": "assumed: pid.codes 0x1209"},
            "product_id": 2, "interface": 0, "endpoint_in": 129, "endpoint_out": 1,
            "protocol_version": 1}})";
  const ParamFile file = ParamFile::parse(text, "tau.json");
  const double limits[6] = {2, 2, 2, 2, 2, 2};
  const DeviceDescriptor d = DeviceDescriptor::fromParams(file, wire::DeviceType{2}, "TAU", 6, 6, limits);
  CHECK(d.vendor_id == 0x1209);
  CHECK(d.product_id == 0x0002);
  CHECK(d.endpoint_in == 0x81);
  CHECK(d.effort_limit[5] == 2.0);

  const char* future = R"({"usb": {"vendor_id": 4617, "product_id": 2, "interface": 0, "endpoint_in": 129,
                                    "endpoint_out": 1, "protocol_version": 7}})";
  CHECK_THROWS_WITH(DeviceDescriptor::fromParams(ParamFile::parse(future, "f.json"), wire::DeviceType{2},
                                                 "TAU", 6, 6, limits),
                    Catch::Contains("f.json") && Catch::Contains("protocol_version 7 is not spoken"));
  const char* bad_endpoint = R"({"usb": {"vendor_id": 4617, "product_id": 2, "interface": 0, "endpoint_in": 1,
                                          "endpoint_out": 1, "protocol_version": 1}})";
  CHECK_THROWS_WITH(DeviceDescriptor::fromParams(ParamFile::parse(bad_endpoint, "e.json"), wire::DeviceType{2},
                                                 "TAU", 6, 6, limits),
                    Catch::Contains("usb/endpoint_in"));
  const double bad_limits[6] = {2, 2, 2, 2, 2, -1};
  const char* ok = R"({"usb": {"vendor_id": 4617, "product_id": 2, "interface": 0, "endpoint_in": 129,
                                "endpoint_out": 1, "protocol_version": 1}})";
  CHECK_THROWS_WITH(DeviceDescriptor::fromParams(ParamFile::parse(ok, "l.json"), wire::DeviceType{2}, "TAU",
                                                 6, 6, bad_limits),
                    Catch::Contains("effort limit of actuator 5"));
}
