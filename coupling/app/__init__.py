"""The application: configuration, command line, progress lines."""
