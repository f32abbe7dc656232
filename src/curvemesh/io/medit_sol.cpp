// filled in by the format's implementation
