// filled in by the quality implementation
