"""What a person reads: the readout of a summary, the report folder's plots and text, pictures, ``dlasweep info``."""
