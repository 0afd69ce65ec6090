/**
 * The S7 address model: one pure parser shared by the S7 and FETCH/WRITE
 * drivers, the CLI and the Node-RED editor.
 */
export { isAddress, parseAddress } from './parse';
export { parseTypeSpec, type TypeSpec } from './type-spec';
export { formatAddress, type TagLocation } from './format';
export { S7_TAG_SYNTAX } from './syntax';
