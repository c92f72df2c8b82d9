"""File formats: the authors' dataset folders, our tree files, and their checksums."""
