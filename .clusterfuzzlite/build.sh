#!/bin/bash -eu
# ClusterFuzzLite's build script: the OSS-Fuzz one (fuzz/oss-fuzz/build.sh).
exec "$SRC/minkq/fuzz/oss-fuzz/build.sh"
