"""The application layer: the command line, the paper's reproduction, figures,
animations and diagram graphs."""
