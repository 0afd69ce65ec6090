export { S7PlusClient } from './client';
