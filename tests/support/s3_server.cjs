// A loopback S3 server for the fetch tests: @20minutes/s3rver (it checks AWS SigV4
// signatures) started through its library API, since its CLI exits silently on Node 20.
// Usage: node s3_server.cjs MODULE_DIR DATA_DIR BUCKET
// Prints the port on the first stdout line; credentials are s3rver's defaults
// (S3RVER / S3RVER).
const [moduleDir, directory, bucket] = process.argv.slice(2);
const S3rver = require(moduleDir);
const server = new S3rver({
  directory,
  address: '127.0.0.1',
  port: 0,
  silent: true,
  configureBuckets: [{ name: bucket, configs: [] }],
});
server.run().then((address) => {
  process.stdout.write(`${address.port}\n`);
}).catch((error) => {
  process.stderr.write(`s3rver failed: ${error}\n`);
  process.exit(1);
});
process.on('SIGTERM', () => server.close().then(() => process.exit(0)));
