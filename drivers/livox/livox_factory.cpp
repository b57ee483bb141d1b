#include "drivers/livox/livox_factory.hpp"

#include <cctype>

#include "core/error.hpp"
#include "drivers/livox/livox_decoder.hpp"

namespace livod::livox {

std::unique_ptr<drivers::LidarDecoder> make_livox_decoder(const drivers::DecoderConfig& config) {
  if (config.metadata || config.calibration) {
    throw Error("Livox " + config.model +
                " needs no --metadata or --calibration file (its packets carry Cartesian points)");
  }
  // The registry matched the model ignoring case and separators; map back to the canonical name.
  std::string key;
  for (const char c : config.model) {
    if (c == '_' || c == ' ') {
      key.push_back('-');
    } else {
      key.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
    }
  }
  for (const char* name : {"AVIA", "HORIZON", "TELE-15", "MID-40", "MID-70", "MID-360", "HAP"}) {
    std::string a;
    std::string b;
    for (const char c : key) {
      if (c != '-') a.push_back(c);
    }
    for (const char* c = name; *c != '\0'; ++c) {
      if (*c != '-') b.push_back(*c);
    }
    if (a == b) return std::make_unique<LivoxDecoder>(*livox_model(name), LivoxDecoderOptions{});
  }
  throw Error("unknown Livox model '" + config.model + "'");
}

}  // namespace livod::livox
