# cmake -DMIGRATIONS_DIR=... -DOUTPUT=... -P EmbedMigrations.cmake
# Compiles the numbered SQL files into the server, so a binary always knows exactly which schema
# versions it understands and never depends on where it was installed from.
file(GLOB files RELATIVE "${MIGRATIONS_DIR}" "${MIGRATIONS_DIR}/*.up.sql")
list(SORT files)
set(body "")
foreach(name IN LISTS files)
  file(READ "${MIGRATIONS_DIR}/${name}" sql)
  string(FIND "${sql}" ")bathyslam_sql\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${name} contains the raw-string delimiter")
  endif()
  string(APPEND body "    {\"${name}\", R\"bathyslam_sql(${sql})bathyslam_sql\"},\n")
endforeach()
file(WRITE "${OUTPUT}.tmp" "// Generated from migrations/ by cmake/EmbedMigrations.cmake; do not edit.
#include \"server/storage/migrations.h\"

namespace bathyslam::storage {

const std::vector<MigrationFile>& embedded_migration_files() {
  static const std::vector<MigrationFile> files = {
${body}  };
  return files;
}

}  // namespace bathyslam::storage
")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
