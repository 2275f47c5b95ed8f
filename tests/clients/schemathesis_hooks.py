# schemathesis hooks for tests/clients/schemathesis.rs (loaded through
# SCHEMATHESIS_HOOKS).
#
# The POST endpoints take a bare GLB as `model/gltf-binary`, whose schema
# is any bytes. schemathesis has no serializer of its own for that media
# type and reports each request body it generates in it as an error: such
# a body is sent as its bytes, as `application/octet-stream` is (glint
# answers 400 to bytes that are not a GLB).
import schemathesis

schemathesis.serializer.alias("model/gltf-binary", "application/octet-stream")
