"""Running multi-device plans: one logical device per ``--devices`` entry (``run``), the copy
passes (``copies``) and the sort-first scissor (``tiles``)."""
