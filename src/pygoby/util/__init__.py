"""Small shared utilities: clocks, geodesy, NMEA, line-based I/O."""
