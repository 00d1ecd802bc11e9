# Every dependency of the product, from Debian 12 packages (scripts/install-deps.sh).

find_package(Threads REQUIRED)
find_package(OpenMP REQUIRED)

# PCL's config pulls in VTK, whose config refers to MPI's C and C++ targets; find MPI first so
# those targets exist (this is why the project enables C as well as CXX).
find_package(MPI REQUIRED COMPONENTS C CXX)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(PCL 1.13 REQUIRED COMPONENTS common kdtree search filters features registration)
find_package(Ceres 2.1 REQUIRED)
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs)
find_package(PostgreSQL REQUIRED)
find_package(OpenSSL REQUIRED)  # SHA-256 of uploads and tokens, random tokens
find_package(ZLIB REQUIRED)     # submap points
find_package(GDAL 3.6 CONFIG REQUIRED)
find_package(PROJ 9 CONFIG REQUIRED)
find_package(nlohmann_json 3.11 REQUIRED)
find_package(CLI11 2 REQUIRED)
find_package(Protobuf REQUIRED)
find_package(gRPC CONFIG REQUIRED)
find_package(GTest REQUIRED)
find_package(benchmark REQUIRED)

# Debian ships OpenVDB's find module, not a config file.
list(APPEND CMAKE_MODULE_PATH "/usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/OpenVDB")
find_package(OpenVDB REQUIRED)

find_program(GRPC_CPP_PLUGIN grpc_cpp_plugin REQUIRED)

# cpp-httplib (the HTTP endpoint): Debian ships a pkg-config file and a compiled library.
find_package(PkgConfig REQUIRED)
pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib>=0.11)
