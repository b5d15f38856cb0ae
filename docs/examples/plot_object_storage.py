"""
Reading from and writing to S3
==============================

Inputs and the output folder of a dataset run may be fsspec URLs (``s3://``, ``gs://``,
``az://``; the ``s3``, ``gcs`` and ``azure`` extras).  Each file is downloaded to a temporary
copy where it is processed, and each output is written locally, then uploaded.  This example
runs against a local S3 server that the build starts (moto's ``ThreadedMotoServer`` on
127.0.0.1, with fake credentials), so it executes offline; against a real bucket, drop the
server and the ``endpoint_url``, and give the credentials as for any boto3 client.
"""

import logging
import os
import socket

import fsspec
from moto.server import ThreadedMotoServer

import hht3d
from hht3d.dataset import run_dataset
from hht3d.results import load_result

logging.getLogger("werkzeug").setLevel(logging.ERROR)  # no log line per request
with socket.socket() as probe:  # a free port
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
server = ThreadedMotoServer(ip_address="127.0.0.1", port=port, verbose=False)
server.start()
os.environ.update(AWS_ACCESS_KEY_ID="fake", AWS_SECRET_ACCESS_KEY="fake", AWS_DEFAULT_REGION="us-east-1")
storage_options = {"client_kwargs": {"endpoint_url": f"http://127.0.0.1:{port}"}}

# %%
# A bucket with the shipped cow in it.
s3 = fsspec.filesystem("s3", **storage_options)
s3.mkdir("scans")
s3.put_file(str(hht3d.data_path("spot.ply")), "scans/in/spot.ply")
print(s3.ls("scans/in"))

# %%
# The dataset run: every ``.ply`` under the prefix, two IMFs each, results and summary written
# under ``s3://scans/out``.  ``storage_options`` reach every read and write.
rows = run_dataset(
    ["s3://scans/in/*.ply"],
    "s3://scans/out",
    scheduler="threads",
    progress=False,
    storage_options=storage_options,
    max_imfs=2,
)
for row in rows:
    print(row.source, row.status, row.vertices, "vertices,", row.imfs, "IMFs")

# %%
# What the run wrote, with sizes.
for path, info in sorted(s3.find("scans/out", detail=True).items()):
    print(f"s3://{path}  {info['size']:,} bytes")

# %%
# A result reads back from its URL.
result = load_result("s3://scans/out/spot_hht.npz", storage_options=storage_options)
print(result)
server.stop()
