"""The live side of predict.py: a stream of readings in, one prediction per line (or per hop, or
per frame) out, at a steady latency and bounded memory."""
