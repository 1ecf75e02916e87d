// fake-haply-service: the stand-in Haply Inverse Service (fake_haply_service.hpp) as a process.
//   fake-haply-service [--port N] [--devices LIST] [--dt S] [--address A]
// Prints "port N" on stdout once listening, then serves until SIGTERM or SIGINT.
#include <signal.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "fake_haply_service.hpp"

namespace {

void usage(FILE* out) {
  std::fprintf(out,
               "usage: fake-haply-service [--port N] [--devices LIST] [--dt S] [--address A]\n"
               "  --port N       port to listen on (default %d; 0 = any free port)\n"
               "  --devices LIST inverse3:ID, verse_grip:ID, wireless_verse_grip:ID, comma-\n"
               "                 separated (default $FAKE_HAPLY_DEVICES, else %s)\n"
               "  --dt S         plant step per received message, s (default %g)\n"
               "  --address A    address to listen on (default 127.0.0.1)\n"
               "Prints \"port N\" once listening; serves until SIGTERM or SIGINT.\n",
               fake_haply::kDefaultPort, fake_haply::kDefaultDevices, fake_haply::kDefaultDt);
}

bool parse_number(const char* text, double* out) {
  char* end = nullptr;
  *out = std::strtod(text, &end);
  return end != text && *end == '\0';
}

}  // namespace

int main(int argc, char** argv) {
  fake_haply::Options opt;
  if (const char* env = std::getenv("FAKE_HAPLY_DEVICES")) opt.devices = env;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      usage(stdout);
      return 0;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "fake-haply-service: %s needs a value\n", arg.c_str());
      usage(stderr);
      return 2;
    }
    const char* value = argv[++i];
    double number = 0;
    if (arg == "--port") {
      if (!parse_number(value, &number) || number < 0 || number > 65535 ||
          number != static_cast<int>(number)) {
        std::fprintf(stderr, "fake-haply-service: bad port '%s'\n", value);
        return 2;
      }
      opt.port = static_cast<int>(number);
    } else if (arg == "--devices") {
      opt.devices = value;
    } else if (arg == "--dt") {
      if (!parse_number(value, &number) || !(number > 0)) {
        std::fprintf(stderr, "fake-haply-service: bad dt '%s'\n", value);
        return 2;
      }
      opt.dt = number;
    } else if (arg == "--address") {
      opt.address = value;
    } else {
      std::fprintf(stderr, "fake-haply-service: unknown option %s\n", arg.c_str());
      usage(stderr);
      return 2;
    }
  }

  // Blocked before the service's thread starts, so that only sigwait below takes them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  fake_haply::Service service(opt);
  std::string error;
  if (!service.start(&error)) {
    std::fprintf(stderr, "fake-haply-service: %s\n", error.c_str());
    return 1;
  }
  std::printf("port %d\n", service.port());
  std::fflush(stdout);

  int sig = 0;
  sigwait(&signals, &sig);
  service.stop();
  return 0;
}
