/**
 * What the client asks the PLC, each request as one Ask (session.ts): its
 * function, body, and the codec's encoder and decoder. The session stamps
 * the sequence number, the session id and the IntegrityId when it sends one;
 * no caller builds a header. Bodies from the codec (each file cites its
 * source: the s7commplus package (MIT)).
 */
import { decodeExploreResponse, encodeExploreRequest, exploreBody, type ExploreRequest, type ExploreResponse } from '../codec/explore';
import { decodeSetVariableResponse, encodeSetVariableRequest, legitimateBody, sessionAttributeRequest } from '../codec/legitimation';
import type { SetVariableRequest, SetVariableResponse } from '../codec/legitimation';
import type { PObject } from '../codec/object';
import type { PValue } from '../codec/pvalue';
import {
  decodeCreateObjectResponse,
  decodeDeleteObjectResponse,
  encodeCreateObjectRequest,
  sessionCreateBody,
  type ClientIdentity,
  type CreateObjectRequest,
  type CreateObjectResponse,
  type ReturnOnly,
} from '../codec/session';
import { encodeCreditRequest, encodeSubscriptionDeleteRequest, subscriptionCreateBody, type CreditRequest } from '../codec/subscription';
import {
  decodeSubStreamedResponse,
  encodeSubStreamedRequest,
  type SubStreamedRequest,
  type SubStreamedResponse,
} from '../codec/substreamed';
import {
  decodeGetMultiVariablesResponse,
  decodeSetMultiVariablesResponse,
  encodeGetMultiVariablesRequest,
  encodeSetMultiVariablesRequest,
  readBody,
  sessionSetupBody,
  writeBody,
  type GetMultiVariablesRequest,
  type ItemAddress,
  type ItemResults,
  type SetMultiVariablesRequest,
  type SetResults,
} from '../codec/variables';
import { FunctionCode, TransportFlags } from '../constants';
import type { Ask, Tell } from './session';

/** GetMultiVariables of these item addresses: each item's value or error. */
export function readAsk(addresses: ItemAddress[]): Ask<GetMultiVariablesRequest, ItemResults> {
  return {
    functionCode: FunctionCode.GetMultiVariables,
    body: readBody(addresses),
    encode: encodeGetMultiVariablesRequest,
    decode: decodeGetMultiVariablesResponse,
  };
}

/** SetMultiVariables of `values` to these item addresses: each item's error. */
export function writeAsk(addresses: ItemAddress[], values: PValue[]): Ask<SetMultiVariablesRequest, SetResults> {
  return {
    functionCode: FunctionCode.SetMultiVariables,
    body: writeBody(addresses, values),
    encode: encodeSetMultiVariablesRequest,
    decode: decodeSetMultiVariablesResponse,
  };
}

/** Explore of `exploreId` with these attributes. */
export function exploreAsk(exploreId: number, attributes: number[]): Ask<ExploreRequest, ExploreResponse> {
  return {
    functionCode: FunctionCode.Explore,
    body: exploreBody(exploreId, attributes),
    encode: encodeExploreRequest,
    decode: decodeExploreResponse,
  };
}

/** The session's own CreateObject (in the null session, before IntegrityIds). */
export function sessionCreateAsk(who: ClientIdentity): Ask<CreateObjectRequest, CreateObjectResponse> {
  return {
    functionCode: FunctionCode.CreateObject,
    body: sessionCreateBody(who),
    encode: encodeCreateObjectRequest,
    decode: decodeCreateObjectResponse,
    transportFlags: TransportFlags.SessionCreate,
  };
}

/** The session setup: ServerSessionVersion written back to session `sessionId`. */
export function sessionSetupAsk(sessionId: number, serverSessionVersion: PValue): Ask<SetMultiVariablesRequest, SetResults> {
  return {
    functionCode: FunctionCode.SetMultiVariables,
    body: sessionSetupBody(sessionId, serverSessionVersion),
    encode: encodeSetMultiVariablesRequest,
    decode: decodeSetMultiVariablesResponse,
  };
}

/** CreateObject of a subscription in the session's container `containerId`. */
export function subscriptionCreateAsk(containerId: number, object: PObject): Ask<CreateObjectRequest, CreateObjectResponse> {
  return {
    functionCode: FunctionCode.CreateObject,
    body: subscriptionCreateBody(containerId, object),
    encode: encodeCreateObjectRequest,
    decode: decodeCreateObjectResponse,
  };
}

/** DeleteObject of the subscription container `containerId` (`v1`: a session of frame version 1). */
export function subscriptionDeleteAsk(containerId: number, v1: boolean): Ask<{ objectId: number; v1?: boolean }, ReturnOnly> {
  return {
    functionCode: FunctionCode.DeleteObject,
    body: { objectId: containerId, v1 },
    encode: encodeSubscriptionDeleteRequest,
    decode: decodeDeleteObjectResponse,
  };
}

/** A subscription's new credit limit, which the PLC does not answer. */
export function creditTell(credit: CreditRequest): Tell<CreditRequest> {
  return { functionCode: FunctionCode.SetVariable, body: credit, encode: encodeCreditRequest, transportFlags: TransportFlags.NoAnswer };
}

/** The password's answer: SetVariable of `address` of session `sessionId`. */
export function legitimateAsk(sessionId: number, address: number, value: PValue): Ask<SetVariableRequest, SetVariableResponse> {
  return {
    functionCode: FunctionCode.SetVariable,
    body: legitimateBody(sessionId, address, value),
    encode: encodeSetVariableRequest,
    decode: decodeSetVariableResponse,
  };
}

/** GetVarSubStreamed of attribute `address` of session `sessionId`. */
export function sessionAttributeAsk(sessionId: number, address: number): Ask<SubStreamedRequest, SubStreamedResponse> {
  return {
    functionCode: FunctionCode.GetVarSubStreamed,
    body: sessionAttributeRequest(sessionId, address),
    encode: encodeSubStreamedRequest,
    decode: (data, opts) => decodeSubStreamedResponse(data, FunctionCode.GetVarSubStreamed, opts),
  };
}
