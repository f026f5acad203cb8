"""Reading and writing files: results (netCDF) and measured records (CSV, netCDF, UFF 58)."""
