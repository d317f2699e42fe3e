"""The torch networks, one file each; their training lives with the estimators in models/."""
