// A headless Chromium driven over W3C WebDriver: Debian's chromedriver as a child
// process, spoken to over HTTP with cpp-httplib. Enough for the dashboard's end-to-end
// test: open a page, run a script in it, take a screenshot.
#pragma once

#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "tools/lib/process.h"

namespace floorpose::testing {

// A TCP port on 127.0.0.1 that was free a moment ago.
inline int FreeLoopbackPort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof addr;
  if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&addr), len) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0)
    throw std::runtime_error("no free loopback port");
  close(fd);
  return ntohs(addr.sin_port);
}

inline std::string Base64Decode(const std::string& in) {
  std::string out;
  int bits = 0;
  unsigned value = 0;
  for (const char c : in) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    if (c >= '0' && c <= '9') v = c - '0' + 52;
    if (c == '+') v = 62;
    if (c == '/') v = 63;
    if (v < 0) continue;  // padding, line breaks
    value = (value << 6) | static_cast<unsigned>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((value >> bits) & 0xff));
    }
  }
  return out;
}

class Browser {
 public:
  // Starts chromedriver and a headless Chromium with a window of width x height CSS
  // pixels. Throws with what is missing when either cannot start.
  Browser(int width, int height, const std::string& log_path) {
    const int port = FreeLoopbackPort();
    driver_ = std::make_unique<tools::ChildProcess>(
        std::vector<std::string>{"/usr/bin/chromedriver", "--port=" + std::to_string(port)},
        log_path);
    if (!driver_->started())
      throw std::runtime_error(
          "cannot start /usr/bin/chromedriver (apt-get install chromium-driver)");
    http_ = std::make_unique<httplib::Client>("127.0.0.1", port);
    http_->set_read_timeout(60, 0);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
    while (true) {
      auto r = http_->Get("/status");
      if (r && r->status == 200 && nlohmann::json::parse(r->body)["value"]["ready"] == true) break;
      if (!driver_->Running() || std::chrono::steady_clock::now() > deadline)
        throw std::runtime_error("chromedriver did not come up; see " + log_path);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    // The flags of a closed network: no background connections, no sandbox as root.
    const nlohmann::json args = {
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-dev-shm-usage",
        "--force-device-scale-factor=1",
        "--window-size=" + std::to_string(width) + "," + std::to_string(height)};
    const nlohmann::json session =
        Call("POST", "/session",
             {{"capabilities",
               {{"alwaysMatch",
                 {{"browserName", "chrome"},
                  {"goog:chromeOptions", {{"binary", "/usr/bin/chromium"}, {"args", args}}}}}}}});
    session_ = "/session/" + session["sessionId"].get<std::string>();
  }
  ~Browser() {
    if (!session_.empty()) http_->Delete(session_);
    if (driver_ && driver_->Running()) driver_->Terminate(std::chrono::seconds(5));
  }

  void Open(const std::string& url) { Call("POST", session_ + "/url", {{"url", url}}); }
  // Runs `script` (a function body; `arguments` holds args) in the page; its return value.
  nlohmann::json Run(const std::string& script, nlohmann::json args = nlohmann::json::array()) {
    return Call("POST", session_ + "/execute/sync", {{"script", script}, {"args", args}});
  }
  // A real mouse click at (x, y) CSS pixels of the viewport (WebDriver actions).
  void Click(double x, double y) {
    Actions({{{"type", "pointer"},
              {"id", "mouse"},
              {"parameters", {{"pointerType", "mouse"}}},
              {"actions",
               {{{"type", "pointerMove"},
                 {"x", std::lround(x)},
                 {"y", std::lround(y)},
                 {"origin", "viewport"}},
                {{"type", "pointerDown"}, {"button", 0}},
                {{"type", "pointerUp"}, {"button", 0}}}}}});
  }
  // A mouse wheel turned by delta_y pixels at (x, y).
  void Wheel(double x, double y, int delta_y) {
    Actions({{{"type", "wheel"},
              {"id", "wheel"},
              {"actions",
               {{{"type", "scroll"},
                 {"x", std::lround(x)},
                 {"y", std::lround(y)},
                 {"deltaX", 0},
                 {"deltaY", delta_y},
                 {"origin", "viewport"}}}}}});
  }
  std::string ScreenshotPng() {
    return Base64Decode(Call("GET", session_ + "/screenshot").get<std::string>());
  }

 private:
  void Actions(const nlohmann::json& sources) {
    Call("POST", session_ + "/actions", {{"actions", sources}});
    Call("DELETE", session_ + "/actions");
  }
  nlohmann::json Call(const std::string& method, const std::string& path,
                      const nlohmann::json& body = nullptr) {
    httplib::Result r = method == "GET" ? http_->Get(path.c_str())
                        : method == "DELETE"
                            ? http_->Delete(path.c_str())
                            : http_->Post(path.c_str(), body.dump(), "application/json");
    if (!r) throw std::runtime_error("WebDriver " + path + ": " + httplib::to_string(r.error()));
    nlohmann::json reply = nlohmann::json::parse(r->body, nullptr, false);
    if (r->status != 200 || reply.is_discarded())
      throw std::runtime_error("WebDriver " + path + ": HTTP " + std::to_string(r->status) + " " +
                               r->body.substr(0, 400));
    return reply["value"];
  }

  std::unique_ptr<tools::ChildProcess> driver_;
  std::unique_ptr<httplib::Client> http_;
  std::string session_;
};

}  // namespace floorpose::testing
