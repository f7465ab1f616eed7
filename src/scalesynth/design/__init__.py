"""From a spec sheet to a chosen robot (``scalesynth design``): the spec schema (``spec``), bounds and configs per
candidate mechanism (``sizing``), the comparison and recommendation (``comparison``), the command's orchestration
(``run``), the datasheet (``datasheet``) and the exports (``export``)."""
