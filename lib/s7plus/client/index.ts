export { S7PlusClient, type InsecureEvent, type PeerCertificate, type S7PlusClientOptions } from './client';
