"""The runtime's jobs, one module each, over one ``rgraph.vk.executor.Executor``'s state:
``setup`` (resources, passes, query pools), ``one_time`` (initialisation and frame 0's
releases), ``commands`` (command buffers from the lowered recording), ``submits`` (prebuilt
submit arrays), ``frames`` (the frame loop and timings), ``readback`` and ``teardown``."""
