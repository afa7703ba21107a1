// Keeps the library non-empty until the first solver sources land.
namespace calstand::solver {}
