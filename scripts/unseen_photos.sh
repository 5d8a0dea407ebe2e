# Sourced by the evaluation scripts (after `cd` to the repository and setting `shared`):
# `unseen_photos DIR` links into DIR the photographs of $shared/backgrounds/photos that the
# repository does not bundle in tests/data/backgrounds/photos, which no training rendering used.
unseen_photos() {
  mkdir -p "$1"
  for photo in "$shared"/backgrounds/photos/*.jpg; do
    [ -e "tests/data/backgrounds/photos/$(basename "$photo")" ] || ln -sf "$(realpath "$photo")" "$1/"
  done
}
