# cmake -DWEB_DIR=... -DOUTPUT=... -P EmbedWebFiles.cmake
# Compiles the web page (server/http/web: the page, its script and style, vendored Leaflet) into
# the server, so that a binary serves the page it was built with, wherever it runs.
file(GLOB_RECURSE files RELATIVE "${WEB_DIR}" "${WEB_DIR}/*.html" "${WEB_DIR}/*.js" "${WEB_DIR}/*.css" "${WEB_DIR}/*.png")
list(SORT files)
set(arrays "")
set(body "")
set(index 0)
foreach(name IN LISTS files)
  file(READ "${WEB_DIR}/${name}" hex HEX)
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
  if(name MATCHES "\\.html$")
    set(type "text/html; charset=utf-8")
  elseif(name MATCHES "\\.js$")
    set(type "text/javascript; charset=utf-8")
  elseif(name MATCHES "\\.css$")
    set(type "text/css; charset=utf-8")
  else()
    set(type "image/png")
  endif()
  string(APPEND arrays "const unsigned char file_${index}[] = {${bytes}};\n")
  string(APPEND body "    {\"/${name}\", {\"${type}\", std::string_view(reinterpret_cast<const char*>(file_${index}), sizeof file_${index})}},\n")
  math(EXPR index "${index} + 1")
endforeach()
file(WRITE "${OUTPUT}.tmp" "// Generated from server/http/web by cmake/EmbedWebFiles.cmake; do not edit.
#include \"server/http/web_files.h\"

namespace bathyslam::server::http {
namespace {

${arrays}
}  // namespace

const std::map<std::string, WebFile, std::less<>>& web_files() {
  static const std::map<std::string, WebFile, std::less<>> files = {
${body}  };
  return files;
}

}  // namespace bathyslam::server::http
")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
