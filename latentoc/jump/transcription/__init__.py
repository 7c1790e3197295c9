"""The jump as an NLP: :mod:`.variables` (the decision vector), :mod:`.selection` (which rows and
samples enter), :mod:`.wiring` (how a row family's nodes see the decision vector) and :mod:`.nlp`
(families, bounds, objective)."""
