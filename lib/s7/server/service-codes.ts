/** The CPU service error codes the simulator answers with (their words: SERVICE_ERRORS in ../constants.ts). */
export const SERVICE_CODE = Object.freeze({
  NOT_IMPLEMENTED: 0x8104,
  STATE: 0x8402,
  NEED_PASSWORD: 0xd241,
  BLOCK_NOT_FOUND: 0xd209,
  NO_BLOCKS: 0xd20e,
  SZL_ID: 0xd401,
  SZL_INDEX: 0xd402,
  SYNTAX: 0xd405,
  WRONG_PASSWORD: 0xd602,
  NO_PASSWORD: 0xd605,
  BAD_TIME: 0xdc01,
});
