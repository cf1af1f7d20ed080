"""Collection of drives, the dataset loader and card, offline corruption."""
