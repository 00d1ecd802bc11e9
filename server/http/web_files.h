#pragma once
// http (web files): the page the endpoint serves at / and its static files (server/http/web,
// compiled in by cmake/EmbedWebFiles.cmake), by path from the web folder ("/index.html",
// "/app.js", "/vendor/leaflet/leaflet.min.js", ...).
#include <functional>
#include <map>
#include <string>
#include <string_view>

namespace bathyslam::server::http {

struct WebFile {
  std::string_view content_type;
  std::string_view bytes;
};

const std::map<std::string, WebFile, std::less<>>& web_files();

}  // namespace bathyslam::server::http
