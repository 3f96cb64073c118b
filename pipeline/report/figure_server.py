"""Imported last in the figure workers' fork server: its imported objects moved out of the garbage
collector's reach (gc.freeze), so that workers forked from it share those pages instead of copying them."""

import gc

gc.collect()
gc.freeze()
